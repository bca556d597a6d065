// One resolved configuration per run: `ecrf encode RUN` rebuilds the file `ecrf train` wrote,
// --lambda-e at the default's value is the default run, --refresh-mask the mask a run computes
// when it ends, a sweep point is the `ecrf train` run of
// its settings, --resume refuses changed settings, and --help shows each rate point's values.
// Small runs of the built-in scene (a few seconds each); every comparison is byte for byte.
#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "tests/common/invoke.h"
#include "tests/common/scoped_temp_dir.h"
#include "tools/cli_args.h"
#include "tools/commands.h"
#include "tools/report/report.h"
#include "tools/train_flags.h"
#include "trainer/data/file_io.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/train_config.h"

namespace ecrf {
namespace tools {
namespace {

using testing_cli::Invoke;

// Short runs that still pass through every phase (upsampling, mask, rate phase, QAT).
const std::vector<std::string> kSmallRun = {"--scene",   "builtin", "--iters",      "100",
                                            "--batch",   "512",     "--final-grid", "48",
                                            "--threads", "2"};

class RunConfigTest : public ::testing::Test {
 protected:
  // Trains kSmallRun plus args into root_/name; returns the run directory.
  std::string Train(const std::string& name, std::vector<std::string> args) {
    const std::string dir = root_ + "/" + name;
    std::vector<std::string> argv = {"train"};
    argv.insert(argv.end(), kSmallRun.begin(), kSmallRun.end());
    argv.insert(argv.end(), args.begin(), args.end());
    argv.insert(argv.end(), {"-o", dir});
    EXPECT_EQ(Invoke(RunTrain, argv), 0) << name;
    return dir;
  }
  static std::vector<uint8_t> Bytes(const std::string& path) {
    return trainer::ReadWholeFile(path);
  }

  const testing_util::ScopedTempDir tmp_{"ecrf_run_config"};
  const std::string root_ = tmp_.path();
};

TEST_F(RunConfigTest, EncodeRunRebuildsTheFileTrainWroteForEveryRatePoint) {
  for (const char* rate : {"low", "medium", "high", "none"}) {
    const std::string run = Train(rate, {"--rate", rate});
    const std::string again = run + "/again.ecrf";
    ASSERT_EQ(Invoke(RunEncode, {"encode", run, "-o", again}), 0);
    EXPECT_EQ(Bytes(again), Bytes(run + "/scene.ecrf")) << "rate point " << rate;
    // The run's configuration is there for every later command, and reads back as the run's.
    const trainer::TrainOptions stored = trainer::TrainConfigFromJson(
        std::string(reinterpret_cast<const char*>(Bytes(run + "/config.json").data()),
                    Bytes(run + "/config.json").size()),
        run);
    EXPECT_STREQ(trainer::NameOf(stored.rate_point), rate);
    std::vector<std::string> args = kSmallRun;
    args.insert(args.end(), {"--rate", rate, "-o", run});
    EXPECT_TRUE(trainer::ChangedSettings(stored, ResolveTrainOptions(args)).empty());
  }
  // A flag that changes a setting changes the file (the run trained 15 levels at the low point).
  const std::string low = root_ + "/low";
  ASSERT_EQ(Invoke(RunEncode, {"encode", low, "-o", low + "/f16.ecrf", "--mlp-levels", "0"}), 0);
  EXPECT_GT(Bytes(low + "/f16.ecrf").size(), Bytes(low + "/scene.ecrf").size());
}

// A run trained with --keep-last-mask is the default run up to its last step; `ecrf encode
// --refresh-mask` computes the mask the default run computes when it ends: the same bytes.
TEST_F(RunConfigTest, EncodeRefreshMaskWritesTheFileOfARunThatRefreshedIt) {
  // 300 iterations: kSmallRun's 100 leave no density for a mask.
  const std::string plain = Train("default", {"--iters", "300"});
  const std::string kept = Train("kept", {"--iters", "300", "--keep-last-mask"});
  EXPECT_NE(Bytes(kept + "/scene.ecrf"), Bytes(plain + "/scene.ecrf"));
  ASSERT_EQ(Invoke(RunEncode, {"encode", kept, "-o", kept + "/again.ecrf"}), 0);
  EXPECT_EQ(Bytes(kept + "/again.ecrf"), Bytes(kept + "/scene.ecrf"));
  ASSERT_EQ(Invoke(RunEncode, {"encode", kept, "--refresh-mask", "-o", kept + "/fresh.ecrf"}), 0);
  EXPECT_EQ(Bytes(kept + "/fresh.ecrf"), Bytes(plain + "/scene.ecrf"));
}

TEST_F(RunConfigTest, LambdaEAtTheDefaultValueWritesTheDefaultRunsBytes) {
  const std::string plain = Train("default", {});
  trainer::TrainOptions medium = trainer::PresetOptions("tiny");
  trainer::ApplyRatePoint("medium", &medium);
  char lambda[32];
  std::snprintf(lambda, sizeof(lambda), "%.9g", double(medium.lambda_e));
  const std::string adjusted = Train("lambda", {"--lambda-e", lambda});
  EXPECT_EQ(Bytes(adjusted + "/scene.ecrf"), Bytes(plain + "/scene.ecrf"));
}

TEST_F(RunConfigTest, ASweepPointWritesTheBytesOfTheTrainRunOfItsSettings) {
  std::vector<std::string> sweep = {"report", "sweep"};
  sweep.insert(sweep.end(), kSmallRun.begin(), kSmallRun.end());
  sweep.insert(sweep.end(), {"--rates", "high", "--targets", "50KB", "--lambdas", "1e-10", "-o",
                             root_ + "/report"});
  ASSERT_EQ(Invoke(RunReportSweep, std::vector<std::string>(sweep.begin() + 1, sweep.end())), 0);
  const std::string high = Train("high", {"--rate", "high"});
  const std::string target = Train("target", {"--target-size", "50KB"});
  const std::string lambda = Train("lambda", {"--lambda-e", "1e-10"});
  EXPECT_EQ(Bytes(root_ + "/report/runs/rate_high/scene.ecrf"), Bytes(high + "/scene.ecrf"));
  EXPECT_EQ(Bytes(root_ + "/report/runs/target_50KB/scene.ecrf"), Bytes(target + "/scene.ecrf"));
  EXPECT_EQ(Bytes(root_ + "/report/runs/lambda_1e-10_steps3/scene.ecrf"),
            Bytes(lambda + "/scene.ecrf"));
  // `ecrf encode RUN` keeps the run's target size: the same bytes, within the size.
  ASSERT_EQ(Invoke(RunEncode, {"encode", target, "-o", target + "/again.ecrf"}), 0);
  EXPECT_EQ(Bytes(target + "/again.ecrf"), Bytes(target + "/scene.ecrf"));
  EXPECT_LE(Bytes(target + "/scene.ecrf").size(), 50000u);
  // report.json records each point's configuration and rate point.
  const nlohmann::json report = ReadReport(root_ + "/report");
  ASSERT_EQ(report["points"].size(), 3u);
  for (const nlohmann::json& p : report["points"]) {
    ASSERT_TRUE(p.contains("config"));
    const trainer::TrainOptions c = trainer::TrainConfigFromJson(p["config"].dump(), "report.json");
    const std::string expected = c.target_bytes > 0 ? "target 50KB"
                                 : c.rate_point == trainer::RatePoint::kMedium
                                     ? "medium base"
                                     : trainer::NameOf(c.rate_point);
    EXPECT_EQ(p["rate_point"], expected);
    if (c.target_bytes == 0) EXPECT_FLOAT_EQ(float(p["lambda_e"].get<double>()), c.lambda_e);
    // A size point's lambda_e is the one it adapted to (it starts from 0, "choose one").
    if (c.target_bytes > 0) EXPECT_GT(p["lambda_e"].get<double>(), 0.0);
  }
  // No point of this sweep is a lambda = 0 float model, so there is no reference to divide by.
  EXPECT_TRUE(report["reference"].is_null()) << report["reference"].dump();
  // A size that cannot name a run directory is refused before anything trains.
  std::vector<std::string> bad(sweep.begin() + 1, sweep.end());
  for (std::string& a : bad) {
    if (a == "50KB") a = "50 KB";
  }
  EXPECT_THROW(Invoke(RunReportSweep, bad), std::invalid_argument);
}

TEST_F(RunConfigTest, ResumeRefusesChangedSettingsUnlessAccepted) {
  const std::string run = Train("stopped", {"--stop-after", "40"});
  std::vector<std::string> resume = {"train"};
  resume.insert(resume.end(), kSmallRun.begin(), kSmallRun.end());
  resume.insert(resume.end(), {"--resume", "--lambda-e", "1e-10", "-o", run});
  std::string error;
  try {
    Invoke(RunTrain, resume);
  } catch (const std::exception& e) {
    error = e.what();
  }
  EXPECT_NE(error.find("lambda_e"), std::string::npos) << error;
  EXPECT_NE(error.find("--accept-config-change"), std::string::npos) << error;
  EXPECT_FALSE(FileExists(run + "/scene.ecrf"));
  resume.push_back("--accept-config-change");
  EXPECT_EQ(Invoke(RunTrain, resume), 0);
  EXPECT_TRUE(FileExists(run + "/scene.ecrf"));
}

// What CLI11 prints as a default: operator<< of the value.
template <class T>
std::string Shown(const T& v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

TEST(TrainHelp, ShowsTheResolvedDefaultsOfEachRatePoint) {
  for (const char* rate : {"low", "medium", "high", "none"}) {
    const trainer::TrainOptions o = ResolveTrainOptions({"--rate", rate});
    testing::internal::CaptureStdout();
    EXPECT_EQ(Invoke(RunTrain, {"train", "--rate", rate, "--help"}), 0);
    std::string help = testing::internal::GetCapturedStdout();
    // The sweep trains each point as `ecrf train` does: its help shows the same values.
    testing::internal::CaptureStdout();
    EXPECT_EQ(Invoke(RunReportSweep, {"sweep", "--rate", rate, "--help"}), 0);
    help += testing::internal::GetCapturedStdout();
    for (const std::string& shown :
         {"--lambda-e X:>= 0=" + Shown(o.lambda_e),
          "--quant-step-scale S:> 0=" + Shown(o.quant_step_scale),
          "--mlp-levels L:in [0, 32767]=" + Shown(o.mlp_levels),
          "--rate-start F:in [0, 1)=" + Shown(o.rate_start),
          "--iters N:in [1, 100000000]=" + Shown(o.iters),
          "--rate TEXT:{none,low,medium,high}=" + std::string(trainer::NameOf(o.rate_point))}) {
      const size_t first = help.find(shown);
      EXPECT_NE(first, std::string::npos) << rate << ": help lacks '" << shown << "'";
      EXPECT_NE(help.find(shown, first + 1), std::string::npos)
          << rate << ": sweep help lacks '" << shown << "'";
    }
  }
  // The encoder's help is help, not a run.
  testing::internal::CaptureStdout();
  EXPECT_EQ(Invoke(RunEncode, {"encode", "--help"}), 0);
  EXPECT_NE(testing::internal::GetCapturedStdout().find("--target-size"), std::string::npos);
}

TEST(TrainHelp, UnknownFlagIsOneShortLineWithASuggestion) {
  testing::internal::CaptureStderr();
  EXPECT_EQ(
      Invoke(RunTrain, {"train", "--scene", "builtin", "--test-strid", "3", "-o", "/tmp/never"}),
      2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(err,
            "ecrf train: error: unknown option '--test-strid' (did you mean --test-stride?); see "
            "'ecrf train "
            "--help'\n");
  EXPECT_FALSE(FileExists("/tmp/never"));
  for (auto command : {RunTrain, RunEncode}) {
    testing::internal::CaptureStderr();
    const std::vector<std::string> args =
        command == RunTrain
            ? std::vector<std::string>{"train", "--scene", "builtin",   "--target-size",
                                       "500",   "-o",      "/tmp/never"}
            : std::vector<std::string>{"encode",          "run",           "-o",
                                       "/tmp/never.ecrf", "--target-size", "500"};
    EXPECT_EQ(Invoke(command, args), 2) << args[0];
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("'500' has no unit: write 500B for bytes or 500KB"), std::string::npos)
        << err;
    EXPECT_EQ(err.find('\n'), err.size() - 1) << "one line: " << err;
  }
  EXPECT_FALSE(FileExists("/tmp/never"));
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
