// Encoder <-> decoder: the decoded grids are the quantized model within the integer IDCT's one
// unit, dead components are dropped without changing the decoded field, the stream is
// deterministic, and the conformance scenes render like their reference images.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "conformance/grid_md5.h"
#include "decoder/camera.h"
#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"
#include "encoder/grid_dct.h"
#include "encoder/scene_encoder.h"
#include "format/coefficients/int_idct.h"
#include "tests/common/decode_or_die.h"
#include "trainer/data/image_io.h"
#include "trainer/data/image_metrics.h"
#include "trainer/rate/coded_model.h"
#include "trainer/train/rate_state.h"

namespace ecrf {
namespace trainer {
namespace {

TensorfModel SmallModel(uint64_t seed) {
  TensorfConfig c;
  c.density_ranks = {3, 4, 2};
  c.app_ranks = {5, 3, 4};
  c.head.num_products = 12;
  c.head.feature_dim = 6;
  c.head.hidden = 16;
  TensorfModel model(c);
  model.Initialize({21, 18, 13}, seed);
  return model;
}

const float* DecodedTensor(const dec::SceneField& f, int g, int t) {
  const dec::VmGrid& grid = g == 0 ? f.density : f.appearance;
  return t < 3 ? grid.plane_f32[t].data() : grid.line_f32[t - 3].data();
}

// Each tensor's step maps its largest block-DCT coefficient to the largest level (127 for 8 bits,
// 32767 for 16), whether computed from the model or from peaks already at hand; a zero peak gets 1.
TEST(SceneCodec, QuantStepsMapEachTensorsPeakToTheLargestLevel) {
  const TensorfModel model = SmallModel(3);
  encoder::RateConfig blocks;
  const std::vector<float> peaks = encoder::PeakCoefficients(DescribeModel(model), blocks);
  for (int coef_bits : {8, 16}) {
    const float max_level = coef_bits == 8 ? 127.f : 32767.f;
    const std::vector<float> steps = ChooseQuantSteps(model, blocks, coef_bits);
    ASSERT_EQ(steps.size(), 12u);
    EXPECT_EQ(steps, encoder::StepsFromPeaks(peaks, coef_bits));
    for (size_t t = 0; t < steps.size(); ++t) {
      ASSERT_GT(peaks[t], 0.f) << t;
      EXPECT_FLOAT_EQ(steps[t] * max_level, peaks[t]) << coef_bits << "-bit tensor " << t;
    }
  }
  EXPECT_EQ(encoder::StepsFromPeaks({0.f, 254.f, 32767.f}, 8),
            (std::vector<float>{1.f, 2.f, 32767.f / 127.f}));
}

// The decoded tensor equals crop(IDCT(round(DCT(G) / step) * step)) within one output unit
// (step / 2^P) plus float rounding: the integer IDCT is the float one up to its final rounding.
TEST(SceneCodec, DecodedGridsAreTheQuantizedModel) {
  for (int coef_bits : {8, 16}) {
    const TensorfModel model = SmallModel(7);
    encoder::EncodeOptions o;
    o.coef_bits = coef_bits;
    o.blocks.plane_block[0] = 4;
    o.blocks.plane_block[1] = 8;
    o.blocks.plane_block[2] = 4;
    o.blocks.line_block[1] = 2;
    o.blocks.line_block[2] = 8;
    encoder::EncodeReport report;
    const std::vector<uint8_t> bytes = EncodeScene(model, o, &report);
    const dec::SceneField field = DecodeOrDie(bytes);
    EXPECT_EQ(report.total_bytes, bytes.size());
    EXPECT_EQ(report.clipped_coefficients, 0u);
    const std::vector<float> steps = ChooseQuantSteps(model, o.blocks, coef_bits);
    const VmGrid* grids[2] = {&model.density(), &model.appearance()};
    double worst_units = 0.0, worst_quant = 0.0;
    for (int g = 0; g < 2; ++g) {
      for (int t = 0; t < 6; ++t) {
        const encoder::GridBlockLayout layout = RateTensorLayout(*grids[g], t, o.blocks);
        std::vector<float> coeffs(layout.num_coeffs());
        encoder::ForwardBlocks(RateTensorData(*grids[g], t), layout, coeffs.data());
        const float step = steps[g * 6 + t];
        EXPECT_EQ(report.steps[g * 6 + t], step);
        for (float& c : coeffs) c = float(std::round(double(c) / step)) * step;
        std::vector<float> expected(layout.tensor_size());
        // InverseBlocks writes through the layout's strides into a tensor of the same storage.
        std::vector<float> storage(t < 3 ? grids[g]->plane_size(t) : grids[g]->line_size(t - 3));
        encoder::InverseBlocks(coeffs.data(), layout, storage.data());
        const float* decoded = DecodedTensor(field, g, t);
        const float* original = RateTensorData(*grids[g], t);
        const double unit = std::ldexp(double(step), -IdctOutputFracBits(coef_bits));
        for (size_t i = 0; i < storage.size(); ++i) {
          worst_units = std::max(worst_units, std::fabs(double(decoded[i]) - storage[i]) / unit);
          worst_quant = std::max(worst_quant, std::fabs(double(decoded[i]) - original[i]) / step);
        }
      }
    }
    EXPECT_LT(worst_units, 1.05) << coef_bits << "-bit";
    // Error against the float model: at most half a step per coefficient, spread by the IDCT.
    EXPECT_LT(worst_quant, 4.0) << coef_bits << "-bit";
    std::printf(
        "  %d-bit: decoded vs float-quantized max %.3f output units; vs model max %.3f steps\n",
        coef_bits, worst_units, worst_quant);
  }
}

TEST(SceneCodec, EncodingIsDeterministicAndMlpPrecisionsAgree) {
  const TensorfModel model = SmallModel(8);
  encoder::EncodeOptions o;
  const std::vector<uint8_t> a = EncodeScene(model, o);
  EXPECT_EQ(a, EncodeScene(model, o));
  o.mlp_float32 = true;
  const std::vector<uint8_t> b = EncodeScene(model, o);
  const dec::SceneField fa = DecodeOrDie(a), fb = DecodeOrDie(b);
  // Same grids; the float32 MLP carries the exact weights, float16 within its precision.
  for (int g = 0; g < 2; ++g) {
    for (int t = 0; t < 6; ++t) {
      const size_t n = t < 3 ? (g ? fa.appearance : fa.density).plane_count(t)
                             : (g ? fa.appearance : fa.density).line_count(t - 3);
      for (size_t i = 0; i < n; ++i)
        ASSERT_EQ(DecodedTensor(fa, g, t)[i], DecodedTensor(fb, g, t)[i]);
    }
  }
  EXPECT_LT(a.size(), b.size());
  const size_t params = model.head().params().size();
  EXPECT_EQ(b.size() - a.size(), params * 2);
}

// Render a few rays of both scenes and return the largest colour difference.
float MaxRenderDifference(const dec::SceneField& a, const dec::SceneField& b) {
  dec::RayMarcher ma, mb;
  EXPECT_TRUE(ma.Init(&a, dec::RenderOptions()).ok());
  EXPECT_TRUE(mb.Init(&b, dec::RenderOptions()).ok());
  const dec::Camera cam = dec::OrbitCamera(24, 24, 0.5f, 0.4f, 3.5f);
  std::vector<float> ia(24 * 24 * 3), ib(24 * 24 * 3);
  EXPECT_TRUE(ma.RenderImage(cam, nullptr, ia.data()).ok());
  EXPECT_TRUE(mb.RenderImage(cam, nullptr, ib.data()).ok());
  float worst = 0.f;
  for (size_t i = 0; i < ia.size(); ++i) worst = std::max(worst, std::fabs(ia[i] - ib[i]));
  return worst;
}

// 1.4 and 1.5 change only how the levels are entropy coded, so the 1.5, 1.4 and 1.3 streams of
// the same model decode to the same grids, mask and MLP to the bit.
// Appearance planes made of smooth bumps of varied widths, like trained features: the spectra of
// neighbouring blocks end at different frequencies.
TensorfModel BumpyModel(int scale = 1, bool textured = false) {
  TensorfModel model = SmallModel(9);
  model.Initialize({48 * scale, 40 * scale, 44 * scale}, 9);
  VmGrid& grid = model.appearance();
  uint32_t state = 12345;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return float(state >> 8) / float(1u << 24);
  };
  for (int m = 0; m < 3; ++m) {
    const int rank = grid.ranks()[m];
    const int h = grid.res()[kMatMode[m][1]], w = grid.res()[kMatMode[m][0]];
    float* plane = grid.plane(m);
    std::fill(plane, plane + size_t(h) * w * rank, 0.f);
    for (int bump = 0; bump < 30 * scale * scale; ++bump) {
      const float cy = next() * h, cx = next() * w, width = 0.7f + 4.f * next(),
                  amp = 2.f * next() - 1.f;
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          const float d2 = ((y - cy) * (y - cy) + (x - cx) * (x - cx)) / (width * width);
          if (d2 > 9.f) continue;
          for (int r = 0; r < rank; ++r)
            plane[(size_t(y) * w + x) * rank + r] += amp * std::exp(-d2) / float(1 + r);
        }
      }
    }
    // A periodic texture over the left part of the plane, each component with its own phase:
    // the same DCT frequencies are significant in neighbouring blocks, as in trained planes.
    for (int y = 0; textured && y < h; ++y) {
      for (int x = 0; x < w / 2; ++x) {
        for (int r = 0; r < rank; ++r) {
          plane[(size_t(y) * w + x) * rank + r] +=
              0.3f * std::sin(2.6f * float(x) + 1.7f * float(y) + 0.9f * float(r)) +
              0.2f * std::sin(0.8f * float(x) - 2.2f * float(y) + 2.1f * float(r));
        }
      }
    }
  }
  return model;
}

TEST(SceneCodec, Version15And14And13StreamsDecodeToTheSameScene) {
  TensorfModel model = BumpyModel(2, /*textured=*/true);
  model.UpdateAlphaMask({9, 8, 6});
  encoder::EncodeOptions o;
  o.mlp_max_level = 31;
  o.blocks.plane_block[0] = 4;
  o.blocks.plane_block[1] = 8;
  o.blocks.plane_block[2] = 8;
  encoder::EncodeReport r15, r14, r13;
  const std::vector<uint8_t> v15 = EncodeScene(model, o, &r15);
  o.max_version_minor = 4;
  const std::vector<uint8_t> v14 = EncodeScene(model, o, &r14);
  o.max_version_minor = 3;
  const std::vector<uint8_t> v13 = EncodeScene(model, o, &r13);
  EXPECT_EQ(v15[5], 5);
  EXPECT_EQ(v14[5], 4);
  EXPECT_EQ(v13[5], 1);  // the quantized MLP's version
  // Each chunk keeps the shortest of its codes, so no tensor grows and some shrink.
  for (int i = 0; i < 12; ++i) {
    EXPECT_LE(r14.tensor_bytes[i], r13.tensor_bytes[i]) << i;
    EXPECT_LE(r15.tensor_bytes[i], r14.tensor_bytes[i]) << i;
  }
  EXPECT_LT(r14.coefficient_bytes(), r13.coefficient_bytes());
  EXPECT_LT(r15.coefficient_bytes(), r14.coefficient_bytes());
  const dec::SceneField a = DecodeOrDie(v14), b = DecodeOrDie(v13), c = DecodeOrDie(v15);
  EXPECT_EQ(conformance::SceneGridMd5(a), conformance::SceneGridMd5(b));
  EXPECT_EQ(conformance::SceneGridMd5(c), conformance::SceneGridMd5(b));
  EXPECT_EQ(conformance::OccupancyMd5(a), conformance::OccupancyMd5(b));
  EXPECT_EQ(conformance::MlpMd5(a), conformance::MlpMd5(b));
  EXPECT_EQ(conformance::MlpMd5(c), conformance::MlpMd5(b));
  o.max_version_minor = 0;  // the quantized MLP needs 1.1
  EXPECT_THROW(EncodeScene(model, o), std::invalid_argument);
}

TEST(SceneCodec, QuantizedMlpIsVersion11SmallerAndRendersAlike) {
  const TensorfModel model = SmallModel(8);
  encoder::EncodeOptions o;
  o.max_version_minor = 3;  // streams for 1.3 decoders carry the lowest version of their features
  const std::vector<uint8_t> f16 = EncodeScene(model, o);
  o.mlp_max_level = 127;
  const std::vector<uint8_t> q = EncodeScene(model, o);
  EXPECT_EQ(f16[5], 0);  // version_minor: streams without the 1.1 feature stay 1.0
  EXPECT_EQ(q[5], 1);
  EXPECT_LT(q.size(), f16.size());
  const dec::SceneField a = DecodeOrDie(f16), b = DecodeOrDie(q);
  // 127 levels per row: each weight within half a step of max|row| / 127 of float16's.
  EXPECT_LT(MaxRenderDifference(a, b), 2e-2f);
}

TEST(SceneCodec, DeadComponentsAreDroppedWithoutChangingTheField) {
  TensorfModel model = SmallModel(9);
  // Density component 1 of mode 0: plane zero. Appearance component 2 of mode 1: line zero.
  // Appearance mode 2: every component's line zero -> the whole mode goes.
  VmGrid& d = model.density();
  for (size_t i = 0; i < d.plane_size(0) / 3; ++i) d.plane(0)[i * 3 + 1] = 0.f;
  VmGrid& a = model.appearance();
  for (size_t i = 0; i < a.line_size(1) / 3; ++i) a.line(1)[i * 3 + 2] = 0.f;
  for (size_t i = 0; i < a.line_size(2); ++i) a.line(2)[i] = 0.f;
  encoder::EncodeOptions o;
  o.blocks.plane_block[0] = 1;  // per-component blocks: zero slices quantize to zero exactly
  o.blocks.line_block[1] = 1;
  encoder::EncodeReport report;
  const std::vector<uint8_t> dropped = EncodeScene(model, o, &report);
  EXPECT_EQ(report.ranks_out[0][0], 2);
  EXPECT_EQ(report.ranks_out[1][1], 2);
  EXPECT_EQ(report.ranks_out[1][2], 0);
  EXPECT_EQ(report.tensor_bytes[6 + 2], 0u);  // appearance plane 2 has no chunk
  o.drop_zero_components = false;
  const std::vector<uint8_t> kept = EncodeScene(model, o);
  EXPECT_LT(dropped.size(), kept.size());
  const dec::SceneField fd = DecodeOrDie(dropped), fk = DecodeOrDie(kept);
  EXPECT_EQ(fd.appearance.total_rank(), 7);  // 5 + (3 - 1) + (4 - 4)
  EXPECT_EQ(fk.appearance.total_rank(), 12);
  EXPECT_LT(MaxRenderDifference(fd, fk), 2e-5f);
}

TEST(SceneCodec, RejectsImpossibleOptions) {
  const TensorfModel model = SmallModel(10);
  encoder::EncodeOptions o;
  o.coef_bits = 12;
  EXPECT_THROW(EncodeScene(model, o), std::invalid_argument);
  o.coef_bits = 8;
  o.steps = {1.f, 2.f};
  EXPECT_THROW(EncodeScene(model, o), std::invalid_argument);
  o.steps.assign(12, 0.f);
  EXPECT_THROW(EncodeScene(model, o), std::invalid_argument);
  o.steps.assign(12, 1e-30f);  // clamped to the smallest legal step: still a valid stream
  EXPECT_EQ(DecodeOrDie(EncodeScene(model, o)).appearance.total_rank(), 12);
}

// One hidden layer (MLPW layers 1): a 1.8 stream whose MLP holds exactly the model's parameters
// (binary32) and colours as the trainer's head does; refused when an older version is asked for.
TEST(SceneCodec, OneHiddenLayerHeadIsVersion18AndDecodesToTheModel) {
  TensorfConfig c = SmallModel(3).config();
  c.head.hidden_layers = 1;
  TensorfModel model(c);
  model.Initialize({21, 18, 13}, 11);
  encoder::EncodeOptions o;
  o.mlp_float32 = true;
  o.mlp_max_level = 0;
  const std::vector<uint8_t> bytes = EncodeScene(model, o);
  EXPECT_EQ(bytes[5], kOneHiddenLayerMinVersionMinor);  // the file header's minor version
  const dec::SceneField field = DecodeOrDie(bytes);
  ASSERT_EQ(field.mlp.config().hidden_layers, 1);
  std::vector<float> params(field.mlp.num_params());
  ASSERT_TRUE(field.mlp.GetParams(params.data(), params.size()).ok());
  EXPECT_EQ(params, model.head().params());
  const int n = 40, P = model.head().config().num_products;
  std::vector<float> prod(size_t(n) * P), vd(3 * n), want(3 * n), got(3 * n);
  for (size_t i = 0; i < prod.size(); ++i) prod[i] = std::sin(0.37f * float(i));
  for (int r = 0; r < n; ++r) {
    const float a = 0.3f * float(r);
    vd[3 * r] = std::cos(a) * 0.6f;
    vd[3 * r + 1] = std::sin(a) * 0.6f;
    vd[3 * r + 2] = 0.8f;
  }
  model.head().Infer(n, prod.data(), vd.data(), want.data());
  std::vector<float> scratch(field.mlp.ScratchFloats());
  field.mlp.Infer(n, prod.data(), P, vd.data(), got.data(), scratch.data());
  for (int i = 0; i < 3 * n; ++i) EXPECT_NEAR(got[i], want[i], 2e-6f) << i;
  o.max_version_minor = kOneHiddenLayerMinVersionMinor - 1;
  EXPECT_THROW(EncodeScene(model, o), std::invalid_argument);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
