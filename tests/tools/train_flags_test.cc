// The training flags as `ecrf train` reads them: the scene model and rate-phase flags this issue
// added, their ranges, and flags left for the caller.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "tools/train_run.h"
#include "trainer/dataset.h"
#include "trainer/scene_fit.h"
#include "trainer/trainer.h"

namespace ecrf {
namespace tools {
namespace {

trainer::TrainOptions Parse(std::vector<std::string> args, std::vector<int>* rest = nullptr,
                            bool rate_point_by_default = false) {
  args.insert(args.begin(), "train");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  std::vector<int> ignored;
  return TrainOptionsFromArgs(int(argv.size()), argv.data(), rest ? rest : &ignored, rate_point_by_default);
}

TEST(TrainFlags, RateStartAndSceneTypeAreReadAndChecked) {
  const trainer::TrainOptions defaults = Parse({"--scene", "forward"});
  EXPECT_FLOAT_EQ(defaults.rate_start, 16000.f / 30000.f);
  EXPECT_EQ(defaults.procedural_scene, "forward");
  EXPECT_EQ(defaults.scene_type, "auto");
  const trainer::TrainOptions o = Parse({"--scene", "forward", "--rate-start", "0.8", "--scene-type", "forward"});
  EXPECT_FLOAT_EQ(o.rate_start, 0.8f);
  EXPECT_EQ(o.scene_type, "forward");
  EXPECT_THROW(Parse({"--rate-start", "1"}), std::invalid_argument);
  EXPECT_THROW(Parse({"--rate-start", "-0.1"}), std::invalid_argument);
  EXPECT_THROW(Parse({"--scene-type", "ndc"}), std::invalid_argument);
  EXPECT_THROW(Parse({"--scene", "sideways"}), std::invalid_argument);
  std::vector<int> rest;
  Parse({"--scene", "forward", "--not-a-training-flag"}, &rest);
  ASSERT_EQ(rest.size(), 1u);
  EXPECT_EQ(rest[0], 3);
}

TEST(TrainFlags, RanksSetDensityAndAppearanceComponents) {
  const trainer::TrainOptions fast = Parse({});
  EXPECT_EQ(fast.density_rank, 16);
  EXPECT_EQ(fast.appearance_rank, 48);
  const trainer::TrainOptions o = Parse({"--ranks", "8,32"});
  EXPECT_EQ(o.density_rank, 8);
  EXPECT_EQ(o.appearance_rank, 32);
  for (const char* bad : {"8", "0,32", "8,", ",8", "8,300", "8,3x", "-1,4"}) {
    EXPECT_THROW(Parse({"--ranks", bad}), std::invalid_argument) << bad;
  }
}

TEST(TrainFlags, MlpHiddenSetsTheWidthOfTheModelsHead) {
  EXPECT_EQ(Parse({}).mlp_hidden, 128);
  const trainer::TrainOptions o = Parse({"--mlp-hidden", "64"});
  EXPECT_EQ(o.mlp_hidden, 64);
  const trainer::TensorfConfig c = trainer::ConfigFor(o, trainer::Dataset(), trainer::SceneFit());
  EXPECT_EQ(c.head.hidden, 64);
  for (const char* bad : {"0", "1025", "6x", "-8"}) {
    EXPECT_THROW(Parse({"--mlp-hidden", bad}), std::invalid_argument) << bad;
  }
}

TEST(TrainFlags, FinalGridSetsWhereUpsamplingEnds) {
  const trainer::TrainOptions o = Parse({"--final-grid", "150"});
  EXPECT_EQ(o.voxels_final, 150L * 150 * 150);
  const std::vector<long> counts = trainer::UpsampleVoxelCounts(o);
  ASSERT_FALSE(counts.empty());
  EXPECT_EQ(counts.back(), o.voxels_final);
  for (size_t i = 1; i < counts.size(); ++i) EXPECT_GT(counts[i], counts[i - 1]);
  // A final grid below the preset's initial one starts there instead of shrinking.
  const trainer::TrainOptions small = Parse({"--final-grid", "40"});
  EXPECT_EQ(small.voxels_init, small.voxels_final);
  for (const char* bad : {"1", "1025", "12x", "-150"}) {
    EXPECT_THROW(Parse({"--final-grid", bad}), std::invalid_argument) << bad;
  }
}

TEST(TrainFlags, UpsampleAtAndMaskAtMoveTheScheduleAndTheRatePhaseFollows) {
  const trainer::TrainOptions o = Parse({"--upsample-at", "200,400,600,800,1000", "--rate-start", "0.1"});
  EXPECT_EQ(o.upsample_iters, (std::vector<int>{200, 400, 600, 800, 1000}));
  // The rate phase still waits for the last upsampling and the last mask update (fast: 900).
  EXPECT_EQ(trainer::RateStartIteration(o), 1001);
  EXPECT_EQ(trainer::UpsampleVoxelCounts(o).back(), o.voxels_final);
  for (const char* bad : {"", "300,200", "0,100", "100,100", "100,x"}) {
    EXPECT_THROW(Parse({"--upsample-at", bad}), std::invalid_argument) << bad;
    EXPECT_THROW(Parse({"--mask-at", bad}), std::invalid_argument) << bad;
  }
  const trainer::TrainOptions early =
      Parse({"--upsample-at", "100,200,300,400,500", "--mask-at", "200,600", "--rate-start", "0.1"});
  EXPECT_EQ(early.alpha_mask_iters, (std::vector<int>{200, 600}));
  EXPECT_EQ(trainer::RateStartIteration(early), 601);
}

TEST(TrainFlags, ARatePointIsADefaultThatOtherFlagsOverrideInAnyOrder) {
  // The low point sets lambda_e, the steps, the head, the components and the grid schedule;
  // flags given before or after it win alike.
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"--rate", "low", "--final-grid", "200", "--rate-start", "0.8", "--lambda-e", "3e-10"},
        std::vector<std::string>{"--final-grid", "200", "--rate-start", "0.8", "--lambda-e", "3e-10", "--rate", "low"}}) {
    const trainer::TrainOptions o = Parse(args, nullptr, /*rate_point_by_default=*/true);
    EXPECT_EQ(o.voxels_final, 200L * 200 * 200);
    EXPECT_FLOAT_EQ(o.rate_start, 0.8f);
    EXPECT_FLOAT_EQ(o.lambda_e, 3e-10f);
    EXPECT_EQ(o.quant_step_scale, 4.0f);  // the point's, not given
    EXPECT_EQ(o.mlp_levels, 15);
  }
  // Without a rate flag the medium point applies; --lambda-e alone keeps the preset's steps.
  EXPECT_FLOAT_EQ(Parse({}, nullptr, true).lambda_e, 3e-11f);
  EXPECT_EQ(Parse({}, nullptr, true).quant_step_scale, 3.0f);
  EXPECT_EQ(Parse({"--lambda-e", "0"}, nullptr, true).quant_step_scale, 1.0f);
  EXPECT_THROW(Parse({"--rate", "extreme"}), std::invalid_argument);
  EXPECT_THROW(Parse({"--rate"}), std::invalid_argument);
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
