// The training flags as `ecrf train` resolves them: preset, then rate point, then every flag;
// ranges, unknown flags and sizes without units.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "decoder/ray_marcher.h"
#include "tests/common/scoped_temp_dir.h"
#include "tools/train_flags.h"
#include "trainer/data/dataset.h"
#include "trainer/data/scene_fit.h"
#include "trainer/train/rate_state.h"
#include "trainer/train/train_config.h"
#include "trainer/train/train_schedule.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {
namespace {

trainer::TrainOptions Parse(std::vector<std::string> args) { return ResolveTrainOptions(args); }

TEST(TrainFlags, RateStartAndSceneTypeAreReadAndChecked) {
  const trainer::TrainOptions defaults = Parse({"--scene", "forward"});
  EXPECT_FLOAT_EQ(defaults.rate_start, 16000.f / 30000.f);  // tiny keeps its schedule at medium
  EXPECT_EQ(defaults.procedural_scene, trainer::ProceduralScene::kForward);
  EXPECT_EQ(defaults.scene_type, trainer::SceneType::kAuto);
  const trainer::TrainOptions o =
      Parse({"--scene", "forward", "--rate-start", "0.8", "--scene-type", "forward"});
  EXPECT_FLOAT_EQ(o.rate_start, 0.8f);
  EXPECT_EQ(o.scene_type, trainer::SceneType::kForward);
  EXPECT_THROW(Parse({"--rate-start", "1"}), std::invalid_argument);
  EXPECT_THROW(Parse({"--rate-start", "-0.1"}), std::invalid_argument);
  EXPECT_THROW(Parse({"--scene-type", "ndc"}), std::invalid_argument);
  EXPECT_THROW(Parse({"--scene", "sideways"}), std::invalid_argument);
}

TEST(TrainFlags, UnknownFlagsAndBareSizesGiveShortErrorsWithTheFix) {
  auto error = [](std::vector<std::string> args) -> std::string {
    try {
      Parse(std::move(args));
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  const std::string unknown = error({"--scene", "builtin", "--lamda-e", "1e-10"});
  EXPECT_NE(unknown.find("unknown option '--lamda-e'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("did you mean --lambda-e?"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("ecrf train --help"), std::string::npos) << unknown;
  EXPECT_EQ(unknown.find('\n'), std::string::npos) << "one line: " << unknown;
  const std::string bare = error({"--target-size", "500"});
  EXPECT_NE(bare.find("has no unit"), std::string::npos) << bare;
  EXPECT_NE(bare.find("500KB"), std::string::npos) << bare;
  EXPECT_EQ(Parse({"--target-size", "500KB"}).target_bytes, 500000u);
  EXPECT_EQ(Parse({"--target-size", "2KiB"}).target_bytes, 2048u);
  EXPECT_EQ(Parse({"--target-size=1.2MB"}).target_bytes, 1200000u);
  EXPECT_NE(error({"--target-size", "5parsecs"}).find("unknown unit"), std::string::npos);
}

TEST(TrainFlags, TheSettingsLineNamesTheRunsOwnMilestones) {
  // The default medium point trains 4500 iterations: the preset's milestones at 3000 scale by 1.5.
  const trainer::TrainOptions o = Parse({"--upsample-at", "200,400,600,800,1000"});
  ASSERT_EQ(o.iters, 4500);
  const std::string line = DescribeSettings(o);
  EXPECT_NE(line.find("upsampling at 300,600,900,1200,1500 of 4500 iterations"), std::string::npos)
      << line;
  EXPECT_NE(
      line.find("rate terms from iteration " + std::to_string(trainer::RateStartIteration(o))),
      std::string::npos)
      << line;
  // Plain TensoRF has no rate phase to name.
  EXPECT_EQ(DescribeSettings(Parse({"--lambda-e", "0"})).find("rate terms"), std::string::npos);
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

TEST(TrainFlags, StepRatioSetsTheModelsSampleSpacing) {
  EXPECT_EQ(Parse({}).step_ratio, 0.5f);
  const trainer::TrainOptions o = Parse({"--step-ratio", "1"});
  EXPECT_EQ(o.step_ratio, 1.f);
  const trainer::TensorfConfig c = trainer::ConfigFor(o, trainer::Dataset(), trainer::SceneFit());
  EXPECT_EQ(c.step_ratio, 1.f);
  for (const char* bad : {"0", "0.1", "5", "x", "-1"}) {
    EXPECT_THROW(Parse({"--step-ratio", bad}), std::invalid_argument) << bad;
  }
}

TEST(TrainFlags, EarlyStopSetsWhereATrainingRayStops) {
  // The default is auto; an object with its cameras kept stops where the renders do.
  EXPECT_EQ(trainer::ConfigFor(Parse({}), trainer::Dataset(), trainer::SceneFit())
                .early_stop_transmittance,
            trainer::kAutoEarlyStop);
  const trainer::TrainOptions o = Parse({"--early-stop", "1e-3"});
  EXPECT_EQ(o.early_stop, 1e-3f);
  const trainer::TensorfConfig c = trainer::ConfigFor(o, trainer::Dataset(), trainer::SceneFit());
  EXPECT_EQ(c.early_stop_transmittance, 1e-3f);
  for (const char* bad : {"0.6", "x"}) {
    EXPECT_THROW(Parse({"--early-stop", bad}), std::invalid_argument) << bad;
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
  // At the preset's own 3000 iterations the milestones fall where they are stated (the default
  // medium point trains 4500, and they scale with it).
  const trainer::TrainOptions o =
      Parse({"--upsample-at", "200,400,600,800,1000", "--rate-start", "0.1", "--iters", "3000"});
  EXPECT_EQ(o.upsample_iters, (std::vector<int>{200, 400, 600, 800, 1000}));
  // The rate phase still waits for the last upsampling and the last mask update (fast: 900).
  EXPECT_EQ(trainer::RateStartIteration(o), 1001);
  EXPECT_EQ(trainer::UpsampleVoxelCounts(o).back(), o.voxels_final);
  for (const char* bad : {"", "300,200", "0,100", "100,100", "100,x"}) {
    EXPECT_THROW(Parse({"--upsample-at", bad}), std::invalid_argument) << bad;
    EXPECT_THROW(Parse({"--mask-at", bad}), std::invalid_argument) << bad;
  }
  const trainer::TrainOptions early = Parse({"--upsample-at", "100,200,300,400,500", "--mask-at",
                                             "200,600", "--rate-start", "0.1", "--iters", "3000"});
  EXPECT_EQ(early.alpha_mask_iters, (std::vector<int>{200, 600}));
  EXPECT_EQ(trainer::RateStartIteration(early), 601);
}

TEST(TrainFlags, ARatePointIsADefaultThatOtherFlagsOverrideInAnyOrder) {
  // The low point sets lambda_e, the steps, the head, the components and the grid schedule;
  // flags given before or after it win alike.
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"--rate", "low", "--final-grid", "200", "--rate-start", "0.8",
                                 "--lambda-e", "3e-10"},
        std::vector<std::string>{"--final-grid", "200", "--rate-start", "0.8", "--lambda-e",
                                 "3e-10", "--rate", "low"}}) {
    const trainer::TrainOptions o = Parse(args);
    EXPECT_EQ(o.voxels_final, 200L * 200 * 200);
    EXPECT_FLOAT_EQ(o.rate_start, 0.8f);
    EXPECT_FLOAT_EQ(o.lambda_e, 3e-10f);
    EXPECT_EQ(o.quant_step_scale, 4.0f);  // the point's, not given
    EXPECT_EQ(o.mlp_levels, 15);
  }
  EXPECT_THROW(Parse({"--rate", "extreme"}), std::invalid_argument);
  EXPECT_THROW(Parse({"--rate"}), std::invalid_argument);
}

TEST(TrainFlags, LambdaEAloneAdjustsTheDefaultPointAndZeroIsPlainTensorf) {
  trainer::TrainOptions medium = trainer::PresetOptions("fast");
  trainer::ApplyRatePoint("medium", &medium);
  const trainer::TrainOptions defaults = Parse({});
  EXPECT_TRUE(trainer::ChangedSettings(medium, defaults).empty());
  EXPECT_EQ(defaults.rate_point, trainer::RatePoint::kMedium);
  // --lambda-e at the default's value is the default run, setting for setting.
  char text[32];
  std::snprintf(text, sizeof(text), "%.9g", double(medium.lambda_e));
  EXPECT_TRUE(trainer::ChangedSettings(defaults, Parse({"--lambda-e", text})).empty());
  // Another value changes lambda_e alone: the steps, levels and schedule stay the point's.
  const std::vector<std::string> changed =
      trainer::ChangedSettings(defaults, Parse({"--lambda-e", "1e-10"}));
  ASSERT_EQ(changed.size(), 1u);
  EXPECT_EQ(changed[0].rfind("lambda_e:", 0), 0u) << changed[0];
  // 0 is plain TensoRF: the "none" point, the preset's schedule and the peak steps.
  trainer::TrainOptions plain = trainer::PresetOptions("fast");
  trainer::ApplyRatePoint("none", &plain);
  EXPECT_TRUE(trainer::ChangedSettings(plain, Parse({"--lambda-e", "0"})).empty());
  EXPECT_TRUE(trainer::ChangedSettings(plain, Parse({"--rate", "none"})).empty());
  EXPECT_EQ(plain.quant_step_scale, 1.0f);
  EXPECT_EQ(plain.voxels_final, trainer::PresetOptions("fast").voxels_final);
  // --target-size picks its own settings by the target's share.
  trainer::TrainOptions target = trainer::PresetOptions("fast");
  target.target_bytes = 600000;
  trainer::ApplyTargetSizeDefaults(&target, trainer::TargetSizeFlagsGiven());
  EXPECT_TRUE(trainer::ChangedSettings(target, Parse({"--target-size", "600KB"})).empty());
  // --rate-start moves the rate phase alone: the finer grid reached sooner stays the target's
  // (chair-800's 45-minute file, docs/results.md).
  const std::vector<std::string> late =
      trainer::ChangedSettings(target, Parse({"--target-size", "600KB", "--rate-start", "0.75"}));
  ASSERT_EQ(late.size(), 1u);
  EXPECT_EQ(late[0].rfind("rate_start:", 0), 0u) << late[0];
}

// `long` is chair-800's 45-minute command written once: the same run as the flags it replaced
// (docs/results.md), setting for setting where the settings mean the same, milestone for
// milestone where a preset states them for its own run length.
TEST(TrainFlags, TheLongPresetIsTheFortyFiveMinuteRunsFlags) {
  for (const char* target : {"500KB", "250KB"}) {
    const trainer::TrainOptions preset = Parse({"--preset", "long", "--target-size", target});
    const trainer::TrainOptions flags =
        Parse({"--head", "deferred", "--early-stop", "1e-4", "--iters", "30000", "--rate-start",
               "0.75", "--target-size", target});
    EXPECT_EQ(trainer::ScaledMilestones(preset.upsample_iters, preset),
              trainer::ScaledMilestones(flags.upsample_iters, flags));
    EXPECT_EQ(trainer::ScaledMilestones(preset.alpha_mask_iters, preset),
              trainer::ScaledMilestones(flags.alpha_mask_iters, flags));
    EXPECT_EQ(trainer::UpsampleVoxelCounts(preset), trainer::UpsampleVoxelCounts(flags));
    EXPECT_EQ(trainer::RateStartIteration(preset), 22500);
    EXPECT_EQ(trainer::RateStartIteration(flags), 22500);
    EXPECT_EQ(trainer::GridFinalIteration(preset), trainer::GridFinalIteration(flags));
    // Early stop is auto in the preset: 1e-4 on chair (an object with its cameras kept).
    const std::vector<std::string> expected = {"early_stop", "fine_grid_rate_start", "preset",
                                               "rate_point_iters"};
    std::vector<std::string> names;
    for (const std::string& line : trainer::ChangedSettings(flags, preset)) {
      names.push_back(line.substr(0, line.find(':')));
    }
    EXPECT_EQ(names, expected) << target;
    EXPECT_LT(preset.early_stop, 0.f);
  }
  // Without a rate point the preset is its plain 20,000 iterations at the coarser grid.
  const trainer::TrainOptions plain = Parse({"--preset", "long", "--rate", "none"});
  EXPECT_EQ(plain.iters, 20000);
  EXPECT_EQ(plain.voxels_final, 180L * 180 * 180);
  // The default rate point is the 30,000-iteration schedule too.
  EXPECT_EQ(trainer::RateStartIteration(Parse({"--preset", "long"})), 22500);
}

// `forward` is flower's 45-minute command (docs/real-captures.md) written once: fast's run at
// the medium rate point with these flags, milestone for milestone.
TEST(TrainFlags, TheForwardPresetIsFlowersFortyFiveMinuteFlags) {
  const trainer::TrainOptions preset = Parse({"--preset", "forward"});
  const trainer::TrainOptions flags =
      Parse({"--head", "deferred", "--refine-cameras", "off", "--iters", "13000"});
  EXPECT_EQ(trainer::ScaledMilestones(preset.upsample_iters, preset),
            trainer::ScaledMilestones(flags.upsample_iters, flags));
  EXPECT_EQ(trainer::ScaledMilestones(preset.alpha_mask_iters, preset),
            trainer::ScaledMilestones(flags.alpha_mask_iters, flags));
  EXPECT_EQ(trainer::UpsampleVoxelCounts(preset), trainer::UpsampleVoxelCounts(flags));
  EXPECT_EQ(trainer::RateStartIteration(preset), trainer::RateStartIteration(flags));
  std::vector<std::string> names;
  for (const std::string& line : trainer::ChangedSettings(flags, preset)) {
    names.push_back(line.substr(0, line.find(':')));
  }
  EXPECT_EQ(names, (std::vector<std::string>{"preset", "rate_point_iters"}));
  // Without a rate point: 10,400 iterations at fast's grid.
  const trainer::TrainOptions plain = Parse({"--preset", "forward", "--rate", "none"});
  EXPECT_EQ(plain.iters, 10400);
  EXPECT_EQ(plain.voxels_final, 180L * 180 * 180);
}

// Without --preset a dataset trains with `fast` unless it is forward-facing (`forward`) or an
// object dataset with given cameras whose training pixels outnumber the rays `fast`'s default
// run draws (`long`).
TEST(TrainFlags, TheDefaultPresetFollowsTheDatasetsSizeAndKind) {
  EXPECT_EQ(trainer::FastRunRays(), int64_t{4500} * 4096);
  const int64_t rays = trainer::FastRunRays();
  using trainer::DataKind;
  EXPECT_EQ(trainer::PresetForData(rays, DataKind::kObjectWithGivenCameras).preset,
            trainer::Preset::kFast);
  EXPECT_EQ(trainer::PresetForData(rays + 1, DataKind::kObjectWithGivenCameras).preset,
            trainer::Preset::kLong);
  EXPECT_EQ(trainer::PresetForData(rays + 1, DataKind::kOther).preset, trainer::Preset::kFast);
  EXPECT_EQ(trainer::PresetForData(1, DataKind::kForwardFacing).preset, trainer::Preset::kForward);

  // Blender layouts with the image size in the JSON: the manifest needs no image.
  testing_util::ScopedTempDir dir("default_preset");
  auto write = [&](const std::string& file, int edge) {
    nlohmann::json root;
    root["camera_angle_x"] = 0.69;
    root["w"] = edge;
    root["h"] = edge;
    for (int i = 0; i < 100; ++i) {
      root["frames"].push_back(
          {{"file_path", "./r_" + std::to_string(i) + ".png"},
           {"transform_matrix", {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 4.0 + i}, {0, 0, 0, 1}}}});
    }
    std::ofstream(dir.path() + "/" + file) << root.dump();
  };
  auto preset = [&](std::vector<std::string> args) {
    args.insert(args.begin(), {"--data", dir.path()});
    return Parse(args).preset;
  };
  write("transforms_train.json", 800);  // 64 M pixels: chair at 800x800
  EXPECT_EQ(preset({}), trainer::Preset::kLong);
  EXPECT_EQ(preset({"--downscale", "2"}), trainer::Preset::kFast);  // 16 M: chair at 400x400
  EXPECT_EQ(preset({"--preset", "fast"}), trainer::Preset::kFast);
  std::string reason;
  BaseTrainOptions({"--data", dir.path()}, &reason);
  EXPECT_EQ(reason,
            "preset long: 64.0 M training pixels, more than the 18.4 M rays of fast's run "
            "(--preset fast: a shorter run)");
  write("transforms_train.json", 400);
  EXPECT_EQ(preset({}), trainer::Preset::kFast);
  // The Instant-NGP layout of a capture whose cameras all look down -z: forward-facing, unless
  // --scene-type says otherwise (then not an object dataset with given cameras either).
  std::filesystem::remove(dir.path() + "/transforms_train.json");
  write("transforms.json", 800);
  for (int i = 0; i < 100; ++i) std::ofstream(dir.path() + "/r_" + std::to_string(i) + ".png");
  EXPECT_EQ(preset({}), trainer::Preset::kForward);
  BaseTrainOptions({"--data", dir.path()}, &reason);
  EXPECT_EQ(reason, "preset forward: every camera looks one way (--preset fast: a shorter run)");
  EXPECT_EQ(preset({"--scene-type", "unbounded"}), trainer::Preset::kFast);
  BaseTrainOptions({"--data", dir.path(), "--scene-type", "unbounded"}, &reason);
  EXPECT_EQ(reason, "preset fast: not an object dataset with given cameras");
  // A folder that is no dataset keeps fast; loading it says why.
  EXPECT_EQ(Parse({"--data", dir.path() + "/missing"}).preset, trainer::Preset::kFast);
}

// Auto early stop: where the renders stop (SPEC.md 7.8) for objects with fixed cameras, the
// whole ray where cameras move or the scene is not an object (not measured there).
TEST(TrainFlags, EarlyStopIsAutoForObjectsWithFixedCameras) {
  EXPECT_EQ(trainer::kAutoEarlyStop, dec::RenderOptions().early_stop_transmittance);
  auto resolved = [](const std::vector<std::string>& args) {
    const trainer::TrainOptions o = Parse(args);
    const trainer::Dataset data = trainer::LoadTrainingViews(o, "train");
    return trainer::ConfigFor(o, data).early_stop_transmittance;
  };
  EXPECT_EQ(resolved({"--scene", "builtin"}), trainer::kAutoEarlyStop);
  EXPECT_EQ(resolved({"--scene", "builtin", "--refine-cameras", "on"}), 0.f);
  EXPECT_EQ(resolved({"--scene", "forward"}), 0.f);
  EXPECT_EQ(resolved({"--scene", "builtin", "--early-stop", "0"}), 0.f);
  EXPECT_EQ(resolved({"--scene", "forward", "--early-stop", "1e-3"}), 1e-3f);
  EXPECT_LT(Parse({"--early-stop", "auto"}).early_stop, 0.f);
}

TEST(TrainFlags, PruneAtIsAListOfIncreasingSharesThatRoundTrips) {
  EXPECT_TRUE(Parse({"--scene", "builtin"}).prune_at.empty());
  const trainer::TrainOptions o =
      Parse({"--scene", "builtin", "--prune-at", "0.4,0.65", "--prune-share", "0.5"});
  EXPECT_EQ(o.prune_at, (std::vector<float>{0.4f, 0.65f}));
  EXPECT_EQ(o.prune_share, 0.5f);
  const trainer::TrainOptions back =
      trainer::TrainConfigFromJson(trainer::TrainConfigToJson(o), "test");
  EXPECT_EQ(back.prune_at, o.prune_at);
  EXPECT_EQ(back.prune_share, 0.5f);
  for (const char* bad : {"0.6,0.4", "1", "0", "0.5,", "x", "-0.2"}) {
    EXPECT_THROW(Parse({"--prune-at", bad}), std::invalid_argument) << bad;
  }
  EXPECT_THROW(Parse({"--prune-share", "0"}), std::invalid_argument);
  EXPECT_THROW(Parse({"--prune-share", "1.5"}), std::invalid_argument);
}

// That every field survives config.json is tests/tools/train_fields_test.cc's; this one checks the
// values a command line gives, floats bit for bit through their shortest decimal.
TEST(TrainFlags, ConfigJsonKeepsACommandLinesValuesExactly) {
  const trainer::TrainOptions o = Parse({"--scene",
                                         "capture",
                                         "--rate",
                                         "low",
                                         "--lambda-e",
                                         "1.5e-10",
                                         "--dct-block",
                                         "8x16x16",
                                         "--ranks",
                                         "8,20",
                                         "--upsample-at",
                                         "100,200",
                                         "--target-size",
                                         "123KB",
                                         "--density-step-factor",
                                         "0.4",
                                         "--mask-downscale",
                                         "3",
                                         "--distortion-loss",
                                         "0.01",
                                         "--tv-density",
                                         "1",
                                         "--tv-app",
                                         "0.5",
                                         "--test-stride",
                                         "3",
                                         "-o",
                                         "run/x"});
  const std::string text = trainer::TrainConfigToJson(o);
  const trainer::TrainOptions back = trainer::TrainConfigFromJson(text, "test");
  EXPECT_TRUE(trainer::ChangedSettings(o, back).empty());
  EXPECT_EQ(trainer::TrainConfigToJson(back), text);
  EXPECT_EQ(back.lambda_e, 1.5e-10f);  // bit for bit, through the shortest decimal
  EXPECT_NE(text.find("\"lambda_e\": 1.5e-10"), std::string::npos) << text;
  EXPECT_EQ(back.test_view_stride, 3);
  EXPECT_EQ(back.density_step_factor, 0.4f);
  EXPECT_EQ(back.mask_downscale, 3);
  EXPECT_EQ(back.distortion_weight, 0.01f);
  EXPECT_EQ(back.tv_weight_density, 1.f);
  EXPECT_EQ(back.tv_weight_app, 0.5f);
  EXPECT_EQ(back.out_dir, "run/x");
  EXPECT_THROW(trainer::TrainConfigFromJson("{\"config_version\": 99, \"settings\": {}}", "x"),
               std::runtime_error);
  EXPECT_THROW(trainer::TrainConfigFromJson("[1, 2]", "x"), std::runtime_error);
  EXPECT_THROW(trainer::TrainConfigFromJson("{\"settings\": {\"iters\": \"many\"}}", "x"),
               std::runtime_error);
}

TEST(TrainFlags, DensityStepFactorScalesTheDensityStepsOnly) {
  EXPECT_EQ(Parse({"--scene", "builtin"}).density_step_factor, 1.0f);
  EXPECT_THROW(Parse({"--scene", "builtin", "--density-step-factor", "0"}), std::invalid_argument);
  trainer::TrainOptions o = Parse({"--scene", "builtin", "--density-step-factor", "0.5"});
  const trainer::Dataset data = trainer::LoadTrainingViews(o, "train");
  trainer::TensorfModel model(trainer::ConfigFor(o, data));
  model.Initialize({24, 20, 16}, 3);
  trainer::RateState halved, plain;
  halved.Activate(model, o);
  o.density_step_factor = 1.0f;
  plain.Activate(model, o);
  ASSERT_EQ(halved.steps.size(), 12u);
  for (int t = 0; t < 12; ++t) {
    EXPECT_EQ(halved.steps[t], t < 6 ? plain.steps[t] * 0.5f : plain.steps[t]) << t;
  }
}

TEST(TrainFlags, DefaultScoringIsAtMostTwentyEvenlySpacedViews) {
  trainer::TrainOptions o;
  EXPECT_EQ(trainer::ScoredTestViewStride(o, 200), 10);  // Synthetic-NeRF: every 10th
  EXPECT_EQ(trainer::ScoredTestViewStride(o, 15), 1);
  EXPECT_EQ(trainer::ScoredTestViewStride(o, 21), 2);
  o.test_view_stride = 1;
  EXPECT_EQ(trainer::ScoredTestViewStride(o, 200), 1);
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
