#include "trainer/train/train_options.h"

#include <gtest/gtest.h>

#include <random>

#include "trainer/data/ray_set.h"
#include "trainer/scenes/builtin_scene.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace trainer {
namespace {

TEST(TrainOptions, MilestonesScaleWithTheRunLength) {
  EXPECT_EQ(ScaleMilestone(2000, 30000, 30000), 2000);
  EXPECT_EQ(ScaleMilestone(2000, 15000, 30000), 1000);
  EXPECT_EQ(ScaleMilestone(7000, 3000, 30000), 700);
}

// Plane TV on auto: TensoRF's LLFF weight for real captures, unbounded or forward-facing, none for
// objects (TensoRF's Blender setting); a weight given, 0 included, is kept for every scene.
TEST(TrainOptions, AutoPlaneTvIsOnForCapturesOnly) {
  const TrainOptions o;
  ASSERT_LT(o.tv_weight_density, 0.f);
  ASSERT_LT(o.tv_weight_app, 0.f);
  EXPECT_EQ(TvWeightFor(o.tv_weight_density, SceneModel::kObject), 0.f);
  EXPECT_EQ(TvWeightFor(o.tv_weight_density, SceneModel::kUnbounded), kCaptureTvWeight);
  EXPECT_EQ(TvWeightFor(o.tv_weight_app, SceneModel::kForward), kCaptureTvWeight);
  EXPECT_EQ(kCaptureTvWeight, 1.f);
  for (SceneModel m : {SceneModel::kObject, SceneModel::kUnbounded, SceneModel::kForward}) {
    EXPECT_EQ(TvWeightFor(0.f, m), 0.f);
    EXPECT_EQ(TvWeightFor(0.25f, m), 0.25f);
  }
}

// --feature-pe and --view-pe reach the head (and through it the file's MLPW header); the sh
// head, which has no MLP, encodes nothing whatever they say.
TEST(TrainOptions, PositionalEncodingFlagsReachTheHead) {
  const Dataset data = MakeBuiltinScene("train", 8, 8, 4, 1);
  TrainOptions o = PresetOptions("tiny");
  EXPECT_EQ(ConfigFor(o, data).head.feature_pe_freqs, 2);  // TensoRF's Blender setting
  EXPECT_EQ(ConfigFor(o, data).head.viewdir_pe_freqs, 2);
  o.feature_pe_freqs = 0;
  o.viewdir_pe_freqs = 5;
  const TensorfConfig mlp = ConfigFor(o, data);
  EXPECT_EQ(mlp.head.feature_pe_freqs, 0);
  EXPECT_EQ(mlp.head.viewdir_pe_freqs, 5);
  o.head = HeadChoice::kSh;
  const TensorfConfig sh = ConfigFor(o, data);
  EXPECT_EQ(sh.head.feature_pe_freqs, 0);
  EXPECT_EQ(sh.head.viewdir_pe_freqs, 0);
}

TEST(TrainOptions, UpsampleCountsAreLogSpacedAndEndAtTheFinalGrid) {
  const TrainOptions o = PresetOptions("paper");
  const auto counts = UpsampleVoxelCounts(o);
  ASSERT_EQ(counts.size(), o.upsample_iters.size());
  EXPECT_EQ(counts.back(), o.voxels_final);
  for (size_t i = 1; i < counts.size(); ++i) {
    // Constant ratio between consecutive steps, as TensoRF's N_voxel_list.
    EXPECT_NEAR(double(counts[i]) / counts[i - 1], double(counts[1]) / counts[0], 0.01);
  }
  const double lo[3] = {-1.5, -1.5, -1.5}, hi[3] = {1.5, 1.5, 1.5};
  int res[3];
  ResolutionForVoxels(300L * 300 * 300, lo, hi, res);
  EXPECT_EQ(res[0], 300);
  const double flat_hi[3] = {1.5, 1.5, 0.0};
  ResolutionForVoxels(128L * 128 * 128, lo, flat_hi, res);
  EXPECT_EQ(res[0], res[1]);
  EXPECT_NEAR(double(res[2]) / res[0], 0.5, 0.02);  // cubic voxels
  EXPECT_THROW(PresetOptions("nonsense"), std::invalid_argument);
}

TEST(TrainOptions, RateTermsStartOnlyOnTheFinalGrid) {
  TrainOptions o = PresetOptions("fast");
  o.rate_start = 0.1f;  // earlier than the last upsample: must be pushed after it
  const int last_upsample = ScaleMilestone(o.upsample_iters.back(), o.iters, o.reference_iters);
  EXPECT_GT(RateStartIteration(o), last_upsample);
  o.rate_start = 0.9f;
  EXPECT_EQ(RateStartIteration(o), int(0.9 * o.iters + 0.5));
}

TEST(RaySet, BatchesCoverEveryRayOncePerEpochAndFilterKeepsMatches) {
  const Dataset d = MakeBuiltinScene("train", 8, 6, 3, 1);
  RaySet rays(d.views);
  EXPECT_EQ(rays.size(), 8u * 6 * 3);
  std::mt19937_64 rng(5);
  std::vector<float> o(3 * 144), dir(3 * 144), rgb(3 * 144);
  rays.NextBatch(144, rng, o.data(), dir.data(), rgb.data());
  // One epoch visits each pixel once: the set of colours equals the set of pixels' colours.
  double sum = 0, expected = 0;
  for (float c : rgb) sum += c;
  for (const View& v : d.views)
    for (float c : v.rgb.pixels) expected += c;
  EXPECT_NEAR(sum, expected, 1e-3);
  for (int i = 0; i < 144; ++i)
    EXPECT_NEAR(
        dir[3 * i] * dir[3 * i] + dir[3 * i + 1] * dir[3 * i + 1] + dir[3 * i + 2] * dir[3 * i + 2],
        1.0, 1e-5);
  rays.Filter([](const float*, const float* d) { return d[0] > 0; });
  EXPECT_GT(rays.size(), 0u);
  EXPECT_LT(rays.size(), 144u);
  rays.NextBatch(16, rng, o.data(), dir.data(), rgb.data());
  for (int i = 0; i < 16; ++i) EXPECT_GT(dir[3 * i], 0.f);
  auto none = [](int n, const float*, const float*, uint8_t* keep) {
    for (int i = 0; i < n; ++i) keep[i] = 0;
  };
  // A filter that would leave fewer rays than asked for changes nothing.
  const size_t before = rays.size();
  EXPECT_FALSE(rays.FilterChunked(none, 1));
  EXPECT_EQ(rays.size(), before);
  EXPECT_TRUE(rays.FilterChunked(none, 0));
  EXPECT_EQ(rays.size(), 0u);
  EXPECT_THROW(rays.NextBatch(1, rng, o.data(), dir.data(), rgb.data()), std::runtime_error);
}

// Sample names each ray's view (the pruning test applies that image's exposure gain), and draws
// the same rays whether it names them or not.
TEST(RaySet, SampleNamesTheViewOfEachRay) {
  const Dataset d = MakeBuiltinScene("train", 8, 6, 3, 1);
  const RaySet rays(d.views);
  std::mt19937_64 a(9), b(9);
  std::vector<float> o(3 * 64), dir(3 * 64), rgb(3 * 64), o2(3 * 64), dir2(3 * 64), rgb2(3 * 64);
  std::vector<uint32_t> views(64, 99);
  rays.Sample(64, a, o.data(), dir.data(), rgb.data(), views.data());
  rays.Sample(64, b, o2.data(), dir2.data(), rgb2.data());
  EXPECT_EQ(rgb, rgb2);
  EXPECT_EQ(dir, dir2);
  std::vector<int> seen(d.views.size(), 0);
  for (int i = 0; i < 64; ++i) {
    ASSERT_LT(views[size_t(i)], d.views.size());
    ++seen[views[size_t(i)]];
    const Camera& c = d.views[views[size_t(i)]].camera;  // a pinhole's rays start at its centre
    for (int k = 0; k < 3; ++k) EXPECT_FLOAT_EQ(o[3 * size_t(i) + size_t(k)], float(c.c2w[k][3]));
  }
  for (const int s : seen) EXPECT_GT(s, 0);
}

TEST(RatePoints, NamedPointsSetLambdaStepsAndMlpLevels) {
  TrainOptions o = PresetOptions("fast");
  ApplyRatePoint("low", &o);
  EXPECT_EQ(o.lambda_e, 2e-10f);
  EXPECT_EQ(o.quant_step_scale, 4.0f);
  EXPECT_EQ(o.mlp_levels, 15);
  EXPECT_EQ(o.appearance_rank, 32);
  EXPECT_EQ(o.density_rank, 16);
  // A finer final grid, reached earlier: the rate phase starts after the upsampling at 1000.
  EXPECT_EQ(o.voxels_final, 220L * 220 * 220);
  EXPECT_EQ(o.upsample_iters, (std::vector<int>{200, 400, 600, 800, 1000}));
  EXPECT_EQ(RateStartIteration(o), 1501);  // 1000 of the 3000-iteration schedule, at 4500
  // 1.5x the preset's iterations; the milestones scale with them.
  EXPECT_EQ(o.iters, 4500);
  EXPECT_EQ(o.reference_iters, 3000);
  TrainOptions tiny = PresetOptions("tiny");  // already below 32 appearance components
  ApplyRatePoint("low", &tiny);
  EXPECT_EQ(tiny.appearance_rank, 24);
  EXPECT_EQ(tiny.mlp_levels, 15);
  // tiny keeps its grid schedule at every rate point (fine_grid_at_rate_points).
  EXPECT_EQ(tiny.voxels_final, PresetOptions("tiny").voxels_final);
  EXPECT_EQ(tiny.upsample_iters, PresetOptions("tiny").upsample_iters);
  EXPECT_EQ(RateStartIteration(tiny), RateStartIteration(PresetOptions("tiny")));
  EXPECT_EQ(tiny.iters, PresetOptions("tiny").iters);
  TrainOptions medium = PresetOptions("fast");
  ApplyRatePoint("medium", &medium);
  EXPECT_EQ(medium.lambda_e, 3e-11f);
  EXPECT_EQ(medium.quant_step_scale, 3.0f);
  EXPECT_EQ(medium.mlp_levels, 31);
  EXPECT_EQ(medium.appearance_rank, 48);
  EXPECT_EQ(medium.voxels_final, 220L * 220 * 220);  // the low point's grid schedule
  EXPECT_EQ(medium.iters, 4500);
  EXPECT_EQ(RateStartIteration(medium), 1501);
  TrainOptions high = PresetOptions("fast");
  ApplyRatePoint("high", &high);
  EXPECT_EQ(high.quant_step_scale, 1.0f);
  EXPECT_EQ(high.voxels_final, 180L * 180 * 180);  // the preset's schedule
  EXPECT_EQ(RateStartIteration(high), RateStartIteration(PresetOptions("fast")));
  EXPECT_EQ(high.iters, 3000);
  EXPECT_THROW(ApplyRatePoint("extreme", &o), std::invalid_argument);
}

TEST(RatePoints, TargetSizeTakesTheStepsOfTheNearestRatePoint) {
  TrainOptions o = PresetOptions("fast");
  const double grid_bytes = NominalFloat32GridBytes(o);
  EXPECT_NEAR(grid_bytes, 25.0e6, 0.1e6);  // 180^3 voxels, 3 x (16 + 48) components
  struct Case {
    size_t target;
    float scale;
    int levels;
    int appearance_rank;
    long voxels_final;
    int iters;
  } cases[] = {{300000, 4.f, 15, 32, 220L * 220 * 220, 4500},
               {600000, 3.f, 31, 48, 220L * 220 * 220, 4500},
               {1000000, 2.f, 127, 48, 180L * 180 * 180, 3000},
               {5000000, 2.f, 127, 48, 180L * 180 * 180, 3000}};
  for (const Case& c : cases) {
    TrainOptions t = o;
    t.target_bytes = c.target;
    ApplyTargetSizeDefaults(&t, TargetSizeFlagsGiven());
    EXPECT_EQ(t.quant_step_scale, c.scale) << c.target;
    EXPECT_EQ(t.mlp_levels, c.levels) << c.target;
    EXPECT_EQ(t.appearance_rank, c.appearance_rank) << c.target;
    EXPECT_EQ(t.density_rank, 16) << c.target;
    EXPECT_EQ(t.voxels_final, c.voxels_final) << c.target;
    EXPECT_EQ(t.iters, c.iters) << c.target;
  }
  // What the user gave stays; without a target nothing changes.
  TrainOptions given = o;
  given.target_bytes = 300000;
  given.quant_step_scale = 2.5f;
  given.mlp_levels = 63;
  given.appearance_rank = 40;
  TargetSizeFlagsGiven all;
  given.iters = 2000;
  all.step_scale = all.mlp_levels = all.ranks = all.schedule = all.iters = true;
  ApplyTargetSizeDefaults(&given, all);
  EXPECT_EQ(given.iters, 2000);
  EXPECT_EQ(given.quant_step_scale, 2.5f);
  EXPECT_EQ(given.mlp_levels, 63);
  EXPECT_EQ(given.appearance_rank, 40);
  EXPECT_EQ(given.voxels_final, o.voxels_final);
  EXPECT_EQ(given.upsample_iters, o.upsample_iters);
  TrainOptions none = o;
  ApplyTargetSizeDefaults(&none, TargetSizeFlagsGiven());
  EXPECT_EQ(none.quant_step_scale, o.quant_step_scale);
  EXPECT_EQ(none.mlp_levels, o.mlp_levels);
  EXPECT_EQ(none.appearance_rank, o.appearance_rank);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
