#include "decoder/ray_marcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "decoder/camera.h"
#include "decoder/field.h"
#include "decoder/field_sampler.h"
#include "tests/common/marcher_checks.h"
#include "tests/common/naive_renderer.h"

namespace ecrf {
namespace dec {
namespace {

using namespace naive;  // NOLINT(google-build-using-namespace): the reference of every test here

TEST(RayMarcherTest, MatchesNaiveReferenceWithMask) {
  TestScene ts;
  BuildScene(SceneSpec(), &ts);
  ExpectMatchesNaive(ts, Exact(), 11);
  RenderOptions no_skip = Exact();
  no_skip.skip_empty_space = false;
  ExpectMatchesNaive(ts, no_skip, 12);
}

TEST(RayMarcherTest, MatchesNaiveReferenceWithoutMask) {
  SceneSpec spec;
  spec.mask_res[0] = 0;
  spec.seed = 8;
  TestScene ts;
  BuildScene(spec, &ts);
  ExpectMatchesNaive(ts, Exact(), 13);
}

// An unbounded scene (SPEC.md 7.2.1): the HEAD box is the region of interest, the grids and the
// mask span the contracted cube; cameras inside and outside the region, rays in every direction.
TEST(RayMarcherTest, UnboundedSceneMatchesNaiveReference) {
  TestScene ts;
  BuildScene(SceneSpec(), &ts);
  SceneField& s = ts.field;
  s.scene_model = SceneModel::kUnbounded;
  s.step_size = 0.04f;
  s.n_samples = 300;
  s.background[1] = 0.f;
  const float cube_min[3] = {-2.f, -2.f, -2.f}, cube_max[3] = {2.f, 2.f, 2.f};
  const int mres[3] = {21, 17, 19};
  ASSERT_TRUE(s.mask.Init(cube_min, cube_max, mres).ok());
  for (int z = 0; z < mres[2]; ++z)
    for (int y = 0; y < mres[1]; ++y)
      for (int x = 0; x < mres[0]; ++x) s.mask.Set(x, y, z, (x * 7 + y * 3 + z) % 5 != 0);
  ASSERT_TRUE(s.mask.BuildAcceleration().ok());
  ASSERT_TRUE(s.Validate().ok()) << s.Validate().message();

  std::mt19937 rng(21);
  std::normal_distribution<float> nrm(0.f, 1.f);
  Rays rays;
  for (int i = 0; i < 240; ++i) {
    float o[3] = {nrm(rng), nrm(rng), nrm(rng)}, d[3] = {nrm(rng), nrm(rng), nrm(rng)};
    Normalize(o);
    for (float& v : o) v *= i % 3 == 0 ? 0.3f : 3.5f;
    if (i % 2 == 0) {
      for (int a = 0; a < 3; ++a) d[a] = 0.1f * d[a] - o[a];  // towards the region
    }
    if (i % 17 == 0) d[i % 3] = 0.f;  // axis-parallel components
    Normalize(d);
    rays.Add(o, d, "camera");
  }
  for (const bool skip : {true, false}) {
    RenderOptions opt = Exact();
    opt.skip_empty_space = skip;
    std::vector<float> rgb, acc;
    RenderStats stats;
    RenderWith(s, opt, rays, &rgb, &acc, &stats);
    double max_err = 0.0, sum_acc = 0.0;
    for (size_t r = 0; r < rays.size(); ++r) {
      double ref[3], ref_acc;
      NaiveRenderUnbounded(ts, &rays.o[3 * r], &rays.d[3 * r], ref, &ref_acc);
      sum_acc += ref_acc;
      for (int k = 0; k < 3; ++k) max_err = std::max(max_err, std::fabs(ref[k] - rgb[3 * r + k]));
      max_err = std::max(max_err, std::fabs(ref_acc - acc[r]));
    }
    EXPECT_LT(max_err, 1e-4);
    EXPECT_GT(sum_acc / rays.size(), 0.05);
    EXPECT_GT(stats.samples, rays.size() * 30);  // rays sample far beyond the region
  }
}

TEST(RayMarcherTest, NearPlaneAndSampleCap) {
  SceneSpec spec;
  TestScene ts;
  BuildScene(spec, &ts);
  ts.field.near_far[0] = 2.f;  // Blender near: rays starting inside begin at t = 2
  ts.field.n_samples = 23;     // explicit sample count (the last sample has dist 0)
  ExpectMatchesNaive(ts, Exact(), 14, 0.01);
  ts.field.n_samples = 0;
  ts.field.step_size = 0.037f;
  ExpectMatchesNaive(ts, Exact(), 15, 0.01);
}

TEST(RayMarcherTest, RankZeroModes) {
  SceneSpec spec;
  spec.dranks[0] = 0;
  spec.dranks[2] = 0;
  spec.aranks[1] = 0;
  spec.blob_amp = 12.f;  // one density mode left: make it dense
  spec.seed = 9;
  TestScene ts;
  BuildScene(spec, &ts);
  ExpectMatchesNaive(ts, Exact(), 16);
  // No appearance components at all (P = 0): colour comes from the MLP biases and viewdirs.
  SceneSpec spec0 = spec;
  spec0.aranks[0] = spec0.aranks[1] = spec0.aranks[2] = 0;
  TestScene ts0;
  BuildScene(spec0, &ts0);
  ExpectMatchesNaive(ts0, Exact(), 17);
}

TEST(RayMarcherTest, OtherMlpWidths) {
  SceneSpec spec;
  spec.mlp.feature_dim = 9;
  spec.mlp.feature_pe_freqs = 3;
  spec.mlp.viewdir_pe_freqs = 0;
  spec.mlp.hidden = 24;
  TestScene ts;
  BuildScene(spec, &ts);
  ExpectMatchesNaive(ts, Exact(), 18);
}

TEST(RayMarcherTest, Int16GridsMatchFloatWithinQuantization) {
  TestScene ts;
  BuildScene(SceneSpec(), &ts);
  TestScene tq;
  BuildScene(SceneSpec(), &tq);  // same seed: same MLP and mask
  VmGrid qd, qa;
  ASSERT_TRUE(QuantizeGridInt16(ts.field.density, &qd).ok());
  ASSERT_TRUE(QuantizeGridInt16(ts.field.appearance, &qa).ok());
  tq.field.density = std::move(qd);
  tq.field.appearance = std::move(qa);
  ASSERT_TRUE(tq.field.Validate().ok());
  // The int16 renderer is exact for its own (dequantized) values...
  ExpectMatchesNaive(tq, Exact(), 19);
  // ...and close to the float scene.
  const Rays rays = MakeRays(ts.field, 20);
  std::vector<float> rf, af, rq, aq;
  RenderWith(ts.field, Exact(), rays, &rf, &af);
  RenderWith(tq.field, Exact(), rays, &rq, &aq);
  double max_diff = 0.0;
  for (size_t i = 0; i < rf.size(); ++i)
    max_diff = std::max(max_diff, double(std::fabs(rf[i] - rq[i])));
  EXPECT_LT(max_diff, 2e-3);
  std::printf("int16 vs float grids: max |rgb diff| = %.3g\n", max_diff);
}

Camera TestCamera(int w, int h) {
  Camera cam = OrbitCamera(w, h, 0.7f, 0.4f, 3.5f);
  cam.fx = cam.fy = 0.9f * w;  // wide enough to see the whole box and some background
  return cam;
}

TEST(RayMarcherTest, SkippingGivesIdenticalImage) {
  TestScene ts;
  BuildScene(SceneSpec(), &ts);
  const Camera cam = TestCamera(48, 40);
  std::vector<float> a(48 * 40 * 3), b(48 * 40 * 3);
  RenderOptions opt;
  opt.early_stop_transmittance = 0.f;
  RayMarcher skip, noskip;
  ASSERT_TRUE(skip.Init(&ts.field, opt).ok());
  opt.skip_empty_space = false;
  ASSERT_TRUE(noskip.Init(&ts.field, opt).ok());
  RenderStats sa, sb;
  ASSERT_TRUE(skip.RenderImage(cam, nullptr, a.data(), &sa).ok());
  ASSERT_TRUE(noskip.RenderImage(cam, nullptr, b.data(), &sb).ok());
  EXPECT_EQ(sa.samples, sb.samples);
  EXPECT_EQ(sa.color_samples, sb.color_samples);
  EXPECT_GT(sa.samples, 0u);
  for (size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "at " << i;
  // The test rays too (axis-parallel, grazing, inside).
  const Rays rays = MakeRays(ts.field, 21);
  std::vector<float> r1, a1, r2, a2;
  RenderOptions o1 = Exact(), o2 = Exact();
  o2.skip_empty_space = false;
  RenderWith(ts.field, o1, rays, &r1, &a1);
  RenderWith(ts.field, o2, rays, &r2, &a2);
  EXPECT_EQ(r1, r2);
  EXPECT_EQ(a1, a2);
}

// A mask fine enough for every skipping level (64^3, 16^3 and 4^3 blocks of cells) to have
// empty blocks: the ball alone, no random voxels. Skipping must still change nothing.
TEST(RayMarcherTest, SkippingAtEveryLevelGivesIdenticalImage) {
  SceneSpec spec;
  spec.mask_res[0] = 150;
  spec.mask_res[1] = 170;
  spec.mask_res[2] = 140;
  spec.random_voxels = false;
  TestScene ts;
  BuildScene(spec, &ts);
  RenderOptions with = Exact(), without = Exact();
  without.skip_empty_space = false;
  const Rays rays = MakeRays(ts.field, 22);
  std::vector<float> r1, a1, r2, a2;
  RenderWith(ts.field, with, rays, &r1, &a1);
  RenderWith(ts.field, without, rays, &r2, &a2);
  EXPECT_EQ(r1, r2);
  EXPECT_EQ(a1, a2);
  const Camera cam = TestCamera(48, 40);
  std::vector<float> a(48 * 40 * 3), b(48 * 40 * 3);
  RayMarcher skip, noskip;
  ASSERT_TRUE(skip.Init(&ts.field, with).ok());
  ASSERT_TRUE(noskip.Init(&ts.field, without).ok());
  RenderStats sa, sb;
  ASSERT_TRUE(skip.RenderImage(cam, nullptr, a.data(), &sa).ok());
  ASSERT_TRUE(noskip.RenderImage(cam, nullptr, b.data(), &sb).ok());
  EXPECT_EQ(a, b);
  EXPECT_EQ(sa.samples, sb.samples);
  EXPECT_GT(sa.samples, 0u);
  // The skip visited fewer positions: less work charged for the same samples.
  EXPECT_LT(sa.work, sb.work);
}

TEST(RayMarcherTest, ThreadCountDoesNotChangeOutput) {
  TestScene ts;
  BuildScene(SceneSpec(), &ts);
  const Camera cam = TestCamera(37, 29);  // ragged tiles
  std::vector<std::vector<uint8_t>> bytes;
  std::vector<std::vector<float>> floats;
  for (int threads : {1, 2, 3}) {
    RenderOptions opt;
    opt.num_threads = threads;
    RayMarcher rm;
    ASSERT_TRUE(rm.Init(&ts.field, opt).ok());
    std::vector<uint8_t> img(37 * 29 * 4);
    std::vector<float> rgb(37 * 29 * 3);
    RenderStats st;
    ASSERT_TRUE(rm.RenderImage(cam, img.data(), rgb.data(), &st).ok());
    EXPECT_EQ(st.rays, 37u * 29u);
    bytes.push_back(img);
    floats.push_back(rgb);
  }
  EXPECT_EQ(bytes[0], bytes[1]);
  EXPECT_EQ(bytes[0], bytes[2]);
  EXPECT_EQ(floats[0], floats[1]);
  EXPECT_EQ(floats[0], floats[2]);
  // RGBA8 is the rounded float image, alpha the opacity.
  for (size_t p = 0; p < 37 * 29; ++p)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(bytes[0][4 * p + k], uint8_t(floats[0][3 * p + k] * 255.f + 0.5f));
}

TEST(RayMarcherTest, EarlyTerminationChangesAlmostNothing) {
  SceneSpec spec;
  spec.blob_amp = 6.f;  // opaque core so that termination actually happens
  TestScene ts;
  BuildScene(spec, &ts);
  const Rays rays = MakeRays(ts.field, 22);
  std::vector<float> r1, a1, r2, a2;
  RenderOptions on = Exact(), off = Exact();
  on.early_stop_transmittance = 1e-4f;
  RenderStats s_on, s_off;
  RenderWith(ts.field, on, rays, &r1, &a1, &s_on);
  RenderWith(ts.field, off, rays, &r2, &a2, &s_off);
  double max_diff = 0.0;
  for (size_t i = 0; i < r1.size(); ++i)
    max_diff = std::max(max_diff, double(std::fabs(r1[i] - r2[i])));
  EXPECT_LE(max_diff, 1.1e-4);
  EXPECT_LT(s_on.samples, s_off.samples);
  EXPECT_EQ(s_on.color_samples, s_off.color_samples);
}

TEST(RayMarcherTest, StepScaleIsTheSceneWithAScaledStep) {
  // SPEC.md 7.8: step_scale s renders exactly the scene whose step is step * s (one binary32
  // product) and whose sample count is ceil(n / s): same bits as changing the scene itself.
  TestScene ts;
  BuildScene(SceneSpec(), &ts);
  const Rays rays = MakeRays(ts.field, 31);
  for (float scale : {0.5f, 2.f, 3.f}) {
    RenderOptions scaled = Exact();
    scaled.step_scale = scale;
    std::vector<float> r1, a1, r2, a2;
    RenderStats s1, s2;
    RenderWith(ts.field, scaled, rays, &r1, &a1, &s1);
    const float step = ts.field.StepSize();
    const int n = ts.field.NumSamples();
    ts.field.step_size = step * scale;
    ts.field.n_samples = int(std::ceil(double(n) / scale));
    RenderWith(ts.field, Exact(), rays, &r2, &a2, &s2);
    EXPECT_EQ(r1, r2) << "scale " << scale;
    EXPECT_EQ(a1, a2) << "scale " << scale;
    EXPECT_EQ(s1.samples, s2.samples);
    // And that scene still matches the naive reference process.
    ExpectMatchesNaive(ts, Exact(), 32, 0.01);
    ts.field.step_size = 0.f;
    ts.field.n_samples = 0;
  }
  RenderOptions fine = Exact(), coarse = Exact();
  fine.step_scale = 0.5f;
  coarse.step_scale = 2.f;
  std::vector<float> r, a;
  RenderStats s_fine, s_coarse;
  RenderWith(ts.field, fine, rays, &r, &a, &s_fine);
  RenderWith(ts.field, coarse, rays, &r, &a, &s_coarse);
  EXPECT_GT(s_fine.samples, 3 * s_coarse.samples);
}

TEST(RayMarcherTest, WeightThresholdOptionOverridesTheScene) {
  TestScene ts;
  BuildScene(SceneSpec(), &ts);
  const Rays rays = MakeRays(ts.field, 33);
  RenderOptions higher = Exact();
  higher.weight_threshold = 0.02f;
  std::vector<float> r1, a1, r2, a2, r0, a0;
  RenderStats s0, s1, s2;
  RenderWith(ts.field, Exact(), rays, &r0, &a0, &s0);
  RenderWith(ts.field, higher, rays, &r1, &a1, &s1);
  const float scene_threshold = ts.field.weight_threshold;
  ts.field.weight_threshold = 0.02f;
  RenderWith(ts.field, Exact(), rays, &r2, &a2, &s2);
  ts.field.weight_threshold = scene_threshold;
  EXPECT_EQ(r1, r2);
  EXPECT_EQ(a1, a0);  // only colour is skipped, opacity is unchanged
  EXPECT_LT(s1.color_samples, s0.color_samples);
  EXPECT_EQ(s1.color_samples, s2.color_samples);
}

// num_samples may legally be 2^20 (a 32x32 view then takes half a minute): the default sample
// budget refuses such a scene at Init, a cap or a coarser step brings it within the budget, and
// 0 lifts the budget.
TEST(RayMarcherTest, SampleBudgetRefusesScenesWithTooManySamplesPerRay) {
  TestScene ts;
  BuildScene(SceneSpec(), &ts);
  ts.field.n_samples = 1 << 20;
  RenderOptions o;
  RayMarcher rm;
  const Status s = rm.Init(&ts.field, o);
  EXPECT_EQ(s.code(), kErrLimit);
  EXPECT_NE(std::string(s.message()).find("1048576 samples per ray"), std::string::npos)
      << s.message();
  o.max_samples = kDefaultSampleBudget;
  EXPECT_TRUE(rm.Init(&ts.field, o).ok());
  o.max_samples = 0;
  o.step_scale = 64.f;  // 16384 samples
  EXPECT_TRUE(rm.Init(&ts.field, o).ok());
  o.step_scale = 32.f;  // 32768 samples
  EXPECT_EQ(rm.Init(&ts.field, o).code(), kErrLimit);
  o.sample_budget = 0;
  EXPECT_TRUE(rm.Init(&ts.field, o).ok());
  o.sample_budget = -1;
  EXPECT_EQ(rm.Init(&ts.field, o).code(), kErrInvalidArgument);
}

// Decoded grids are finite by construction and not rescanned; grids a program wrote itself are.
TEST(RayMarcherTest, NonFiniteGridValuesAreRefusedUnlessKnownFinite) {
  TestScene ts;
  BuildScene(SceneSpec(), &ts);
  ASSERT_FALSE(ts.field.grids_known_finite);
  ts.field.appearance.plane_f32[0][3] = NAN;
  RayMarcher rm;
  EXPECT_EQ(rm.Init(&ts.field, RenderOptions()).code(), kErrCorrupt);
}

TEST(RayMarcherTest, RejectsSpeedKnobsOutOfRange) {
  TestScene ts;
  BuildScene(SceneSpec(), &ts);
  for (float bad : {0.f, 1.f / 32, 65.f, NAN}) {
    RenderOptions o;
    o.step_scale = bad;
    RayMarcher rm;
    EXPECT_EQ(rm.Init(&ts.field, o).code(), kErrInvalidArgument) << bad;
  }
  for (float bad : {1.5f, NAN}) {
    RenderOptions o;
    o.weight_threshold = bad;
    RayMarcher rm;
    EXPECT_EQ(rm.Init(&ts.field, o).code(), kErrInvalidArgument) << bad;
  }
}

TEST(RayMarcherTest, EmptyDensityRendersBackground) {
  // Empty alpha mask: every sample is skipped, the image is exactly white with alpha 0.
  SceneSpec spec;
  spec.empty_mask = true;
  TestScene ts;
  BuildScene(spec, &ts);
  const Camera cam = TestCamera(20, 16);
  std::vector<uint8_t> img(20 * 16 * 4);
  std::vector<float> rgb(20 * 16 * 3);
  RayMarcher rm;
  ASSERT_TRUE(rm.Init(&ts.field, RenderOptions()).ok());
  RenderStats st;
  ASSERT_TRUE(rm.RenderImage(cam, img.data(), rgb.data(), &st).ok());
  EXPECT_EQ(st.samples, 0u);
  for (size_t p = 0; p < 20 * 16; ++p) {
    for (int k = 0; k < 3; ++k) EXPECT_EQ(rgb[3 * p + k], 1.f);
    EXPECT_EQ(img[4 * p + 3], 0);
    EXPECT_EQ(img[4 * p], 255);
  }
  // No mask, density feature -100 everywhere: white up to float rounding.
  SceneSpec spec2;
  spec2.mask_res[0] = 0;
  TestScene t2;
  BuildScene(spec2, &t2);
  for (int m = 0; m < 3; ++m) {
    for (size_t i = 0; i < t2.field.density.plane_count(m); ++i)
      t2.field.density.plane_f32[m][i] = 0.f;
    for (size_t i = 0; i < t2.field.density.line_count(m); ++i)
      t2.field.density.line_f32[m][i] = 0.f;
  }
  for (size_t i = 0; i < t2.field.density.plane_count(0); i += t2.field.density.ranks[0]) {
    t2.field.density.plane_f32[0][i] = -10.f;
  }
  for (size_t i = 0; i < t2.field.density.line_count(0); i += t2.field.density.ranks[0]) {
    t2.field.density.line_f32[0][i] = 10.f;
  }
  RayMarcher rm2;
  ASSERT_TRUE(rm2.Init(&t2.field, RenderOptions()).ok());
  ASSERT_TRUE(rm2.RenderImage(cam, img.data(), rgb.data(), &st).ok());
  EXPECT_GT(st.samples, 0u);
  EXPECT_EQ(st.color_samples, 0u);
  for (size_t p = 0; p < 20 * 16; ++p) {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(rgb[3 * p + k], 1.f, 1e-6);
    EXPECT_EQ(img[4 * p + 3], 0);
  }
}

// Streams that pass every decoder check can still overflow the rendering arithmetic (binary32
// MLP weights of +-3e38, grid values near the float range from steps of 2^64): the infinities
// become NaN inside, and every pixel must still come out as a number in [0, 1] (SPEC.md 1.2, Clip3
// and Max of NaN).
TEST(RayMarcherTest, OverflowingStreamsStillRenderDefinedPixels) {
  for (int kind = 0; kind < 2; ++kind) {
    SCOPED_TRACE(kind == 0 ? "MLP weights of +-3e38" : "grid values of +-3e38");
    TestScene ts;
    BuildScene(SceneSpec(), &ts);
    if (kind == 0) {
      for (size_t i = 0; i < ts.mlp_params.size(); ++i)
        ts.mlp_params[i] = (i % 3 == 0 ? -3e38f : 3e38f);
      ASSERT_TRUE(ts.field.mlp.SetParams(ts.mlp_params.data(), ts.mlp_params.size()).ok());
    } else {
      for (VmGrid* g : {&ts.field.density, &ts.field.appearance}) {
        for (int m = 0; m < 3; ++m) {
          for (size_t i = 0; i < g->plane_count(m); ++i)
            g->plane_f32[m][i] = (i % 2 ? 3e38f : -3e38f);
          for (size_t i = 0; i < g->line_count(m); ++i)
            g->line_f32[m][i] = (i % 3 ? 3e38f : -3e38f);
        }
      }
    }
    const Camera cam = TestCamera(24, 20);
    std::vector<uint8_t> img(24 * 20 * 4);
    std::vector<float> rgb(24 * 20 * 3);
    RayMarcher rm;
    ASSERT_TRUE(rm.Init(&ts.field, RenderOptions()).ok());
    RenderStats st;
    ASSERT_TRUE(rm.RenderImage(cam, img.data(), rgb.data(), &st).ok());
    ASSERT_GT(st.samples, 0u);
    // The MLP case must run the MLP to test it; the grid case may end as NaN density before any
    // colour is evaluated.
    if (kind == 0) ASSERT_GT(st.color_samples, 0u);
    for (size_t p = 0; p < 24 * 20; ++p) {
      for (int k = 0; k < 3; ++k) {
        const float v = rgb[3 * p + k];
        ASSERT_TRUE(v >= 0.f && v <= 1.f) << "pixel " << p << " channel " << k << " is " << v;
      }
    }
  }
}

TEST(RayMarcherTest, BlackBackground) {
  TestScene ts;
  BuildScene(SceneSpec(), &ts);
  ts.field.background[0] = ts.field.background[1] = ts.field.background[2] = 0.f;
  ExpectMatchesNaive(ts, Exact(), 23);
}

TEST(RayMarcherTest, CameraConvention) {
  Camera cam;  // identity pose
  cam.width = 4;
  cam.height = 2;
  cam.fx = cam.fy = 2.f;
  cam.cx = 2.f;
  cam.cy = 1.f;
  cam.c2w[3] = 1.f;
  cam.c2w[7] = 2.f;
  cam.c2w[11] = 3.f;
  float o[3], d[3];
  CameraRay(cam, 0, 0, o, d);  // top-left pixel: left (-x), up (+y), forward (-z)
  EXPECT_EQ(o[0], 1.f);
  EXPECT_EQ(o[1], 2.f);
  EXPECT_EQ(o[2], 3.f);
  const float e[3] = {-0.75f, 0.25f, -1.f};
  const float l = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(d[a], e[a] / l, 1e-6);
}

TEST(RayMarcherTest, RejectsInvalidInput) {
  TestScene ts;
  BuildScene(SceneSpec(), &ts);
  RayMarcher rm;
  RenderOptions opt;
  opt.num_threads = -1;
  EXPECT_EQ(rm.Init(&ts.field, opt).code(), kErrInvalidArgument);
  EXPECT_EQ(rm.Init(nullptr, RenderOptions()).code(), kErrInvalidArgument);
  Camera cam = TestCamera(8, 8);
  std::vector<uint8_t> img(64 * 4);
  EXPECT_EQ(rm.RenderImage(cam, img.data(), nullptr).code(), kErrInvalidArgument);  // no Init
  ASSERT_TRUE(rm.Init(&ts.field, RenderOptions()).ok());
  EXPECT_EQ(rm.RenderImage(cam, nullptr, nullptr).code(), kErrInvalidArgument);
  cam.width = 1 << 14;
  cam.height = 1 << 14;
  EXPECT_EQ(rm.RenderImage(cam, img.data(), nullptr).code(), kErrLimit);
  cam = TestCamera(8, 8);
  cam.fx = NAN;
  EXPECT_EQ(rm.RenderImage(cam, img.data(), nullptr).code(), kErrInvalidArgument);
  // Mismatched MLP width.
  TestScene bad;
  BuildScene(SceneSpec(), &bad);
  MlpConfig mc = bad.field.mlp.config();
  mc.num_products += 1;
  ASSERT_TRUE(bad.field.mlp.Init(mc).ok());
  EXPECT_EQ(rm.Init(&bad.field, RenderOptions()).code(), kErrInvalidArgument);
  // Mask changed without rebuilding the acceleration.
  TestScene m;
  BuildScene(SceneSpec(), &m);
  m.field.mask.Set(0, 0, 0, true);
  EXPECT_EQ(rm.Init(&m.field, RenderOptions()).code(), kErrInvalidArgument);
  // Allocation limits.
  VmGrid g;
  const int huge[3] = {kMaxGridRes, kMaxGridRes, kMaxGridRes}, ranks[3] = {kMaxRank, 1, 1};
  EXPECT_EQ(g.Allocate(huge, ranks, GridStorage::kFloat32).code(), kErrLimit);
  const int too_big[3] = {kMaxGridRes + 1, 2, 2};
  EXPECT_EQ(g.Allocate(too_big, ranks, GridStorage::kFloat32).code(), kErrLimit);
}

}  // namespace
}  // namespace dec
}  // namespace ecrf
