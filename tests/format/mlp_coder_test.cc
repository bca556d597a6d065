#include "format/mlp_coder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "format/half_float.h"

namespace ecrf {
namespace {

MlpLayout Layout(int F, int P, int H, int Ff, int Fv, int layers = 2) {
  return MakeMlpLayout(F, P, H, Ff, Fv, layers);
}

// Gaussian weights whose rows differ in scale by up to 2^12, a zero row, and one row whose
// values are below binary16's smallest step.
std::vector<float> Weights(const MlpLayout& l, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.f, 1.f);
  std::vector<float> w(MlpParamCount(l));
  for (size_t i = 0; i < w.size(); ++i) w[i] = n(rng) * std::ldexp(1.f, int(rng() % 13) - 8);
  MlpMatrixSpan m[4], b[3];
  MlpMatrices(l, m, b);
  for (int c = 0; c < m[1].cols; ++c) w[m[1].offset + 2 * size_t(m[1].cols) + c] = 0.f;
  for (int c = 0; c < m[2].cols; ++c) w[m[2].offset + c] *= 1e-9f;
  return w;
}

TEST(MlpCoder, LayoutCoversEveryParameterOnce) {
  const MlpLayout l = Layout(27, 144, 128, 2, 2);
  MlpMatrixSpan m[4], b[3];
  MlpMatrices(l, m, b);
  EXPECT_EQ(l.input_dim, 150);
  EXPECT_EQ(MlpParamCount(l), size_t(27 * 144 + 128 * 150 + 128 + 128 * 128 + 128 + 3 * 128 + 3));
  // Stream order of 6.6: B, W1, b1, W2, b2, W3, b3, back to back.
  EXPECT_EQ(m[1].offset, m[0].offset + size_t(m[0].rows) * m[0].cols);
  EXPECT_EQ(b[0].offset, m[1].offset + size_t(m[1].rows) * m[1].cols);
  EXPECT_EQ(m[2].offset, b[0].offset + size_t(b[0].cols));
  EXPECT_EQ(b[2].offset + 3, MlpParamCount(l));
  EXPECT_EQ(MlpContextGroup(l, 1, 26), 1);
  EXPECT_EQ(MlpContextGroup(l, 1, 27), 2);
  EXPECT_EQ(MlpContextGroup(l, 1, 30), 3);
  EXPECT_EQ(MlpContextGroup(l, 1, 30 + 108), 4);
  EXPECT_EQ(MlpContextGroup(l, 3, 0), 6);
}

// One hidden layer (MLPW layers 1): W2 and b2 hold no value, W3 follows b1.
TEST(MlpCoder, OneHiddenLayerHasNoSecondLayer) {
  const MlpLayout l = Layout(27, 144, 128, 2, 2, 1);
  MlpMatrixSpan m[4], b[3];
  MlpMatrices(l, m, b);
  EXPECT_EQ(MlpParamCount(l), size_t(27 * 144 + 128 * 150 + 128 + 3 * 128 + 3));
  EXPECT_EQ(m[2].rows * m[2].cols + b[1].cols, 0);
  EXPECT_EQ(m[3].offset, b[0].offset + 128);
  EXPECT_EQ(b[2].offset + 3, MlpParamCount(l));
}

// The four header bytes in the order of SPEC.md 6.6: the reserved byte, then each field's value
// (unsupported when unknown) and its version (corrupt before it).
TEST(MlpCoder, ChunkHeaderFieldsAndTheirVersions) {
  struct Case {
    uint8_t bytes[4];
    int version_minor, hidden;
    ErrorCode code;
  };
  const Case cases[] = {{{2, 1, 1, 0}, 8, 128, kOk},  // quantized, deferred, one hidden layer
                        {{0, 0, 0, 0}, 0, 128, kOk},  // a 1.0 stream
                        {{2, 1, 1, 0}, 7, 128, kErrCorrupt},       // one layer before 1.8
                        {{2, 1, 2, 0}, 8, 128, kErrUnsupported},   // a later layers value
                        {{2, 1, 1, 0}, 8, 0, kErrCorrupt},         // one layer without an MLP
                        {{2, 1, 0, 1}, 8, 128, kErrCorrupt},       // the reserved byte
                        {{3, 1, 1, 1}, 8, 128, kErrCorrupt},       // the reserved byte first
                        {{3, 0, 0, 0}, 8, 128, kErrUnsupported},   // precision
                        {{2, 0, 0, 0}, 0, 128, kErrCorrupt},       // quantized before 1.1
                        {{0, 1, 0, 0}, 5, 128, kErrCorrupt},       // deferred before 1.6
                        {{0, 2, 0, 0}, 8, 128, kErrUnsupported}};  // head
  for (const Case& c : cases) {
    ByteReader r(c.bytes, 4);
    MlpChunkHeader h;
    const Status s = ReadMlpChunkHeader(&r, c.version_minor, c.hidden, &h);
    EXPECT_EQ(s.code(), c.code) << int(c.bytes[0]) << int(c.bytes[1]) << int(c.bytes[2])
                                << int(c.bytes[3]) << " in 1." << c.version_minor << ": "
                                << s.message();
    if (s.ok()) EXPECT_EQ(MlpHiddenLayers(h.layers), c.bytes[2] == 1 ? 1 : 2);
  }
  ByteReader short_payload(cases[0].bytes, 3);
  MlpChunkHeader h;
  EXPECT_EQ(ReadMlpChunkHeader(&short_payload, 8, 128, &h).code(), kErrTruncated);
}

TEST(MlpCoder, RoundTripIsWhatTheEncoderPredictsAndErrorIsHalfAStep) {
  for (int max_level : {1, 15, 127, 20000, 1 << 20}) {
    const MlpLayout l = Layout(6, 10, 16, 1, 2, max_level == 127 ? 1 : 2);
    const std::vector<float> w = Weights(l, 3 + max_level);
    std::vector<float> predicted;
    const std::vector<uint8_t> payload = EncodeQuantizedMlp(l, w.data(), max_level, &predicted);
    std::vector<float> decoded(w.size(), -7.f);
    const Status s = DecodeQuantizedMlp(l, payload.data(), payload.size(), decoded.data());
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(decoded, predicted) << "max level " << max_level;
    MlpMatrixSpan m[4], b[3];
    MlpMatrices(l, m, b);
    for (const MlpMatrixSpan& mat : m) {
      for (int r = 0; r < mat.rows; ++r) {
        float peak = 0.f;
        for (int c = 0; c < mat.cols; ++c)
          peak = std::fmax(peak, std::fabs(w[mat.offset + size_t(r) * mat.cols + c]));
        const float step = HalfToFloat(FloatToHalf(peak / float(max_level)));
        for (int c = 0; c < mat.cols; ++c) {
          const size_t i = mat.offset + size_t(r) * mat.cols + c;
          // Rounded to the row's step (binary16 steps round the step, not the error bound).
          EXPECT_LE(std::fabs(decoded[i] - w[i]),
                    step > 0.f ? 0.5001f * step + 1e-6f * std::fabs(w[i]) : std::fabs(w[i]) + 0.f);
        }
      }
    }
    for (const MlpMatrixSpan& bias : b) {
      for (int c = 0; c < bias.cols; ++c)
        EXPECT_EQ(decoded[bias.offset + c], HalfToFloat(FloatToHalf(w[bias.offset + c])));
    }
  }
}

TEST(MlpCoder, FewerLevelsFewerBytes) {
  const MlpLayout l = Layout(27, 144, 128, 2, 2);
  const std::vector<float> w = Weights(l, 9);
  const size_t b127 = EncodeQuantizedMlp(l, w.data(), 127, nullptr).size();
  const size_t b31 = EncodeQuantizedMlp(l, w.data(), 31, nullptr).size();
  EXPECT_LT(b31, b127);
  EXPECT_LT(b127, MlpParamCount(l));  // under a byte per weight at 8-bit levels
}

TEST(MlpCoder, EveryTruncationAndNonFiniteHeaderValueIsAnError) {
  const MlpLayout l = Layout(6, 10, 16, 1, 2);
  const std::vector<float> w = Weights(l, 5);
  const std::vector<uint8_t> payload = EncodeQuantizedMlp(l, w.data(), 127, nullptr);
  std::vector<float> out(w.size());
  for (size_t n = 0; n < payload.size(); ++n) {
    EXPECT_FALSE(DecodeQuantizedMlp(l, payload.data(), n, out.data()).ok()) << "prefix " << n;
  }
  std::vector<uint8_t> bad = payload;
  bad[1] = 0x7C;  // first step: binary16 infinity
  bad[0] = 0x00;
  const Status s = DecodeQuantizedMlp(l, bad.data(), bad.size(), out.data());
  EXPECT_EQ(s.code(), kErrCorrupt);
  // Random garbage never crashes and never yields non-finite weights when it succeeds.
  std::mt19937 rng(1);
  for (int t = 0; t < 300; ++t) {
    std::vector<uint8_t> g = payload;
    for (int k = 0; k < 4; ++k) g[rng() % g.size()] = uint8_t(rng());
    if (DecodeQuantizedMlp(l, g.data(), g.size(), out.data()).ok()) {
      for (float v : out) ASSERT_TRUE(std::isfinite(v));
    }
  }
}

}  // namespace
}  // namespace ecrf
