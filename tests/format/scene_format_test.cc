// The scene-level pieces of format/: binary16 conversion, the HEAD chunk and occupancy coding.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "format/half_float.h"
#include "format/occupancy_coder.h"
#include "format/scene_header.h"

namespace ecrf {
namespace {

TEST(HalfFloat, EveryHalfRoundTripsThroughFloat) {
  for (uint32_t h = 0; h < 65536; ++h) {
    const float f = HalfToFloat(uint16_t(h));
    if (std::isnan(f)) {
      EXPECT_TRUE(std::isnan(HalfToFloat(FloatToHalf(f)))) << h;
      continue;
    }
    EXPECT_EQ(FloatToHalf(f), h) << h;
  }
}

TEST(HalfFloat, KnownValuesAndRounding) {
  EXPECT_EQ(FloatToHalf(1.f), 0x3C00);
  EXPECT_EQ(FloatToHalf(-2.f), 0xC000);
  EXPECT_EQ(FloatToHalf(65504.f), 0x7BFF);
  EXPECT_EQ(FloatToHalf(65520.f), 0x7C00);           // rounds to infinity
  EXPECT_EQ(FloatToHalf(5.9604645e-8f), 0x0001);     // smallest subnormal
  EXPECT_EQ(FloatToHalf(2.9802322e-8f), 0x0000);     // half of it: tie to even (zero)
  EXPECT_EQ(FloatToHalf(1.f + 1.f / 2048), 0x3C00);  // tie between 1 and 1+2^-10: even
  EXPECT_EQ(FloatToHalf(1.f + 3.f / 2048), 0x3C02);  // tie: rounds up to even
  EXPECT_FALSE(HalfIsFinite(0x7C00));
  EXPECT_TRUE(HalfIsFinite(0x7BFF));
}

TEST(HalfFloat, NearestForRandomFloats) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-70000.f, 70000.f);
  for (int i = 0; i < 100000; ++i) {
    const float f = u(rng) * (i % 2 ? 1e-4f : 1.f);
    const uint16_t h = FloatToHalf(f);
    const float back = HalfToFloat(h);
    if (std::isinf(back)) {
      EXPECT_GE(std::fabs(f), 65504.f);
      continue;
    }
    // No neighbouring half is closer.
    for (int d : {-1, 1}) {
      const uint16_t n = uint16_t(h + d);
      if (!HalfIsFinite(n) || ((n ^ h) & 0x8000)) continue;
      EXPECT_LE(std::fabs(back - f), std::fabs(HalfToFloat(n) - f)) << f;
    }
  }
}

SceneHeader SampleHeader() {
  SceneHeader h;
  h.aabb_min[0] = -0.7f;
  h.aabb_max[2] = 1.2f;
  h.res[0] = 100;
  h.res[1] = 97;
  h.res[2] = 203;
  h.ranks[0][0] = 16;
  h.ranks[0][1] = 0;
  h.ranks[0][2] = 5;
  h.ranks[1][0] = 48;
  h.ranks[1][1] = 47;
  h.ranks[1][2] = 1;
  h.step_size = 0.0123f;
  h.num_samples = 777;
  h.background[1] = 0.25f;
  h.has_occupancy = 1;
  return h;
}

TEST(SceneHeader, RoundTripsEveryField) {
  const SceneHeader h = SampleHeader();
  ByteWriter w;
  WriteSceneHeader(h, 0, &w);
  ASSERT_EQ(w.size(), kSceneHeaderBytes);
  SceneHeader back;
  ASSERT_TRUE(ParseSceneHeader(w.bytes().data(), w.size(), 0, &back).ok());
  ByteWriter again;
  WriteSceneHeader(back, 0, &again);
  EXPECT_EQ(again.bytes(), w.bytes());
  EXPECT_EQ(back.aabb_min[0], -0.7f);
  EXPECT_EQ(back.res[2], 203);
  EXPECT_EQ(back.ranks[0][2], 5);
  EXPECT_EQ(back.num_samples, 777u);
  EXPECT_EQ(back.background[1], 0.25f);
  EXPECT_EQ(back.has_occupancy, 1);
  int extent[3];
  SceneTensorExtent(back, 1, 1, extent);  // appearance plane 1 spans x (columns) and z (rows)
  EXPECT_EQ(extent[0], 47);
  EXPECT_EQ(extent[1], 203);
  EXPECT_EQ(extent[2], 100);
  SceneTensorExtent(back, 0, 5, extent);  // density line 2 runs along x
  EXPECT_EQ(extent[0], 1);
  EXPECT_EQ(extent[1], 5);
  EXPECT_EQ(extent[2], 100);
}

// From version 1.9 HEAD carries a 91st byte, density_activation (6.2); older streams have 90 bytes
// and softplus. The length follows the stream's version, whatever the byte holds.
TEST(SceneHeader, TheDensityActivationByteFollowsTheVersion) {
  SceneHeader h = SampleHeader();
  h.density_activation = static_cast<uint8_t>(DensityActivation::kRelu);
  ByteWriter w9;
  WriteSceneHeader(h, kDensityActivationMinVersionMinor, &w9);
  ASSERT_EQ(w9.size(), kSceneHeaderBytes + 1);
  EXPECT_EQ(w9.bytes().back(), 1);
  SceneHeader back;
  ASSERT_TRUE(ParseSceneHeader(w9.bytes().data(), w9.size(), 9, &back).ok());
  EXPECT_EQ(back.density_activation, 1);
  // A 1.8 stream has no such byte: the 91-byte payload is damaged, the 90-byte one softplus.
  EXPECT_EQ(ParseSceneHeader(w9.bytes().data(), w9.size(), 8, &back).code(), kErrCorrupt);
  ByteWriter w8;
  WriteSceneHeader(h, 8, &w8);
  ASSERT_EQ(w8.size(), kSceneHeaderBytes);
  EXPECT_EQ(std::vector<uint8_t>(w9.bytes().begin(), w9.bytes().end() - 1), w8.bytes());
  ASSERT_TRUE(ParseSceneHeader(w8.bytes().data(), w8.size(), 8, &back).ok());
  EXPECT_EQ(back.density_activation, 0);
  EXPECT_EQ(ParseSceneHeader(w8.bytes().data(), w8.size(), 9, &back).code(), kErrCorrupt);
  // Values this version does not know are for a newer decoder.
  h.density_activation = kNumDensityActivations;
  ByteWriter w2;
  WriteSceneHeader(h, 9, &w2);
  const Status s = ParseSceneHeader(w2.bytes().data(), w2.size(), 9, &back);
  EXPECT_EQ(s.code(), kErrUnsupported) << s.message();
  EXPECT_NE(std::strstr(s.message(), "density activation"), nullptr) << s.message();
}

// Each mutation breaks one rule; the parser must name it with the right category.
TEST(SceneHeader, RejectsInvalidFields) {
  struct Case {
    const char* what;
    void (*mutate)(SceneHeader*);
    int code;
  };
  const Case cases[] = {
      {"empty box", [](SceneHeader* h) { h->aabb_max[1] = h->aabb_min[1]; }, kErrCorrupt},
      {"nan box", [](SceneHeader* h) { h->aabb_min[2] = NAN; }, kErrCorrupt},
      {"res 1", [](SceneHeader* h) { h->res[0] = 1; }, kErrLimit},
      {"res 4097", [](SceneHeader* h) { h->res[2] = 4097; }, kErrLimit},
      {"rank 1025", [](SceneHeader* h) { h->ranks[0][1] = 1025; }, kErrLimit},
      {"too many values",
       [](SceneHeader* h) {
         h->res[0] = h->res[1] = h->res[2] = 4096;
         h->ranks[1][0] = 1000;
       },
       kErrLimit},
      {"no appearance",
       [](SceneHeader* h) { h->ranks[1][0] = h->ranks[1][1] = h->ranks[1][2] = 0; }, kErrCorrupt},
      {"step 0", [](SceneHeader* h) { h->step_size = 0.f; }, kErrCorrupt},
      {"no samples", [](SceneHeader* h) { h->num_samples = 0; }, kErrLimit},
      {"near > far", [](SceneHeader* h) { h->near_far[0] = 7.f; }, kErrCorrupt},
      {"background 2", [](SceneHeader* h) { h->background[0] = 2.f; }, kErrCorrupt},
      {"hidden 1025", [](SceneHeader* h) { h->hidden = 1025; }, kErrLimit},
      // hidden 0 is the spherical-harmonics colour: 3 (D + 1)^2 features, no encoding (6.2).
      {"hidden 0, 27 features with encodings", [](SceneHeader* h) { h->hidden = 0; }, kErrCorrupt},
      {"hidden 0, 26 features",
       [](SceneHeader* h) {
         h->hidden = 0;
         h->feature_dim = 26;
         h->feature_pe_freqs = h->viewdir_pe_freqs = 0;
       },
       kErrCorrupt},
      {"pe 17", [](SceneHeader* h) { h->viewdir_pe_freqs = 17; }, kErrLimit},
      {"occupancy 2", [](SceneHeader* h) { h->has_occupancy = 2; }, kErrCorrupt},
  };
  for (const Case& c : cases) {
    SceneHeader h = SampleHeader();
    c.mutate(&h);
    ByteWriter w;
    WriteSceneHeader(h, 0, &w);
    SceneHeader back;
    const Status s = ParseSceneHeader(w.bytes().data(), w.size(), 0, &back);
    EXPECT_EQ(s.code(), c.code) << c.what << ": " << s.message();
    EXPECT_NE(std::strstr(s.message(), "HEAD"), nullptr) << c.what;
  }
  ByteWriter w;
  WriteSceneHeader(SampleHeader(), 0, &w);
  SceneHeader back;
  EXPECT_EQ(ParseSceneHeader(w.bytes().data(), w.size() - 1, 0, &back).code(), kErrCorrupt);
}

std::vector<uint8_t> DecodeVolume(const std::vector<uint8_t>& stream, const int res[3],
                                  Status* status,
                                  OccupancyContextSet set = OccupancyContextSet::kNarrow) {
  std::vector<uint8_t> bits(OccupancyBytes(res), 0xAB);
  *status = DecodeOccupancy(stream.data(), stream.size(), res, set, bits.data());
  std::vector<uint8_t> voxels(size_t(res[0]) * res[1] * res[2]);
  for (size_t i = 0; i < voxels.size(); ++i) voxels[i] = OccupancyBit(bits.data(), i);
  return voxels;
}

TEST(OccupancyCoder, RoundTripsStructuredAndRandomVolumes) {
  const int shapes[][3] = {{2, 2, 2}, {7, 6, 5}, {33, 17, 9}, {64, 64, 64}};
  std::mt19937 rng(3);
  for (const auto& res : shapes) {
    const size_t n = size_t(res[0]) * res[1] * res[2];
    for (int kind = 0; kind < 4; ++kind) {
      std::vector<uint8_t> v(n);
      for (int z = 0; z < res[2]; ++z)
        for (int y = 0; y < res[1]; ++y)
          for (int x = 0; x < res[0]; ++x) {
            const double dx = 2.0 * x / res[0] - 1, dy = 2.0 * y / res[1] - 1,
                         dz = 2.0 * z / res[2] - 1;
            uint8_t bit = 0;
            if (kind == 1) bit = 1;
            if (kind == 2) bit = dx * dx + dy * dy + dz * dz < 0.5;
            if (kind == 3) bit = rng() & 1;
            v[(size_t(z) * res[1] + y) * res[0] + x] = bit;
          }
      const std::vector<uint8_t> stream = EncodeOccupancy(v.data(), res);
      Status s;
      EXPECT_EQ(DecodeVolume(stream, res, &s), v)
          << res[0] << "x" << res[1] << "x" << res[2] << " kind " << kind;
      EXPECT_TRUE(s.ok()) << s.message();
      const std::vector<uint8_t> wide = EncodeOccupancy(v.data(), res, OccupancyContextSet::kWide);
      EXPECT_EQ(DecodeVolume(wide, res, &s, OccupancyContextSet::kWide), v)
          << res[0] << "x" << res[1] << "x" << res[2] << " kind " << kind << " wide";
      EXPECT_TRUE(s.ok()) << s.message();
      if (kind == 0 && n >= 64 * 64 * 64) {
        EXPECT_LT(stream.size(), 40u) << "empty volumes must cost almost nothing";
      }
      if (kind == 2 && n >= 64 * 64 * 64) {
        EXPECT_LT(stream.size() * 8.0 / n, 0.05)
            << "a smooth solid costs well under a bit per voxel";
      }
    }
  }
}

// Trained masks are shells and blobs whose outline drifts from slice to slice: the wide set sees
// the previous slice around the voxel, the narrow set only the voxel below it.
TEST(OccupancyCoder, WideContextsCodeDriftingOutlinesInFewerBytes) {
  const int res[3] = {96, 80, 72};
  std::vector<uint8_t> v(size_t(res[0]) * res[1] * res[2]);
  for (int z = 0; z < res[2]; ++z)
    for (int y = 0; y < res[1]; ++y)
      for (int x = 0; x < res[0]; ++x) {
        // A wobbly ellipsoid shell with a tilted axis, two voxels thick.
        const double dx = (x - 48.0 - 0.2 * z) / 40, dy = (y - 40.0) / 30, dz = (z - 36.0) / 33;
        const double r = std::sqrt(dx * dx + dy * dy + dz * dz) *
                         (1 + 0.08 * std::sin(0.31 * x) * std::cos(0.27 * y + 0.1 * z));
        v[(size_t(z) * res[1] + y) * res[0] + x] = r > 0.85 && r < 0.9;
      }
  const std::vector<uint8_t> narrow = EncodeOccupancy(v.data(), res);
  const std::vector<uint8_t> wide = EncodeOccupancy(v.data(), res, OccupancyContextSet::kWide);
  Status s;
  EXPECT_EQ(DecodeVolume(wide, res, &s, OccupancyContextSet::kWide), v);
  EXPECT_TRUE(s.ok()) << s.message();
  EXPECT_LT(wide.size(), narrow.size() * 0.9) << wide.size() << " vs " << narrow.size();
}

TEST(OccupancyCoder, TruncatedStreamsAreErrors) {
  const int res[3] = {20, 20, 20};
  std::vector<uint8_t> v(8000);
  std::mt19937 rng(9);
  for (auto& b : v) b = (rng() % 3) == 0;
  const std::vector<uint8_t> stream = EncodeOccupancy(v.data(), res);
  for (size_t cut = 0; cut < stream.size(); ++cut) {
    Status s;
    DecodeVolume(std::vector<uint8_t>(stream.begin(), stream.begin() + cut), res, &s);
    EXPECT_FALSE(s.ok()) << "prefix of " << cut << " bytes decoded";
  }
}

}  // namespace
}  // namespace ecrf
