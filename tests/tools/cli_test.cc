// The command lines of render, eval, info, selfcheck, conformance, report, bench and `ecrf`
// itself, in-process: --help exits 0 and shows each flag with its type and the default the
// command would use (never running the command), an unknown flag is one line with the nearest
// flag, `ecrf help CMD` is `ecrf CMD --help`, and render/eval use every core by default.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"
#include "ecrf/decoder.h"
#include "format/container.h"
#include "tests/common/invoke.h"
#include "tests/common/scoped_temp_dir.h"
#include "tests/common/small_model.h"
#include "tools/bench/benches.h"
#include "tools/cli.h"
#include "tools/commands.h"
#include "tools/report/report.h"
#include "trainer/train/train_options.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {
namespace {

using testing_cli::Invoke;

const std::string kScene = std::string(ECRF_SOURCE_DIR) + "/tests/conformance/scene_builtin.ecrf";

struct Output {
  int rc = 0;
  std::string out, err;
};

Output Capture(int (*command)(int, char**), const std::vector<std::string>& args) {
  Output r;
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  r.rc = Invoke(command, args);
  r.out = ::testing::internal::GetCapturedStdout();
  r.err = ::testing::internal::GetCapturedStderr();
  return r;
}

// The line of a CLI11 help text that starts with flag ("  --early-stop T:FLOAT in [0 - 1]=0.0001
// ..."), or "" when the help does not list the flag.
std::string FlagLine(const std::string& help, const std::string& flag) {
  std::istringstream in(help);
  std::string line;
  while (std::getline(in, line)) {
    const size_t start = line.find_first_not_of(' ');
    if (start == std::string::npos || line.compare(start, flag.size(), flag) != 0) continue;
    const size_t after = start + flag.size();
    if (after < line.size() && line[after] != ' ' && line[after] != ',') continue;  // a longer flag
    return line;
  }
  return "";
}

// The help lists flag, with "=value" as its default when value is given (CLI11 writes the
// default right after the type, before the description).
void ExpectFlag(const std::string& help, const std::string& flag, const std::string& value = "") {
  const std::string line = FlagLine(help, flag);
  EXPECT_FALSE(line.empty()) << flag << " missing from\n" << help;
  if (value.empty()) return;
  const std::string shown = "=" + value;
  const size_t at = line.find(shown);
  EXPECT_TRUE(at != std::string::npos &&
              (at + shown.size() == line.size() || line[at + shown.size()] == ' '))
      << flag << ": '" << line << "' does not show the default '" << shown << "'";
}

template <typename T>
std::string Text(T value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

// What --help shows for the flags render and eval share, from the renderer's own defaults.
void ExpectRenderFlags(const std::string& help) {
  const dec::RenderOptions defaults;
  ExpectFlag(help, "--threads", "0");
  EXPECT_NE(help.find("0 = all cores: " + std::to_string(AllCores())), std::string::npos);
  ExpectFlag(help, "--int16");
  ExpectFlag(help, "--no-skip");
  ExpectFlag(help, "--early-stop", Text(defaults.early_stop_transmittance));
  ExpectFlag(help, "--samples", Text(defaults.max_samples));
  ExpectFlag(help, "--step-scale", Text(defaults.step_scale));
  EXPECT_NE(FlagLine(help, "--step-scale")
                .find("[" + Text(dec::kMinStepScale) + " - " + Text(dec::kMaxStepScale) + "]"),
            std::string::npos);
  ExpectFlag(help, "--weight-threshold", "the scene's");
  ExpectFlag(help, "--max-memory-mb", Text(dec::kDefaultDecodeMemoryBudget >> 20));
  ExpectFlag(help, "--sample-budget", Text(dec::kDefaultSampleBudget));
  ExpectFlag(help, "--work-budget", Text(dec::kDefaultWorkBudget));
  ExpectFlag(help, "--decode-budget", Text(dec::kDefaultDecodeWorkPerByte));
}

// A parse error: exit code 2 and one line on stderr, "ecrf CMD: error: ..." ("ecrf: error: ..."
// for command ""), containing `expected`.
void ExpectOneLineError(const Output& r, const std::string& command, const std::string& expected) {
  EXPECT_EQ(r.rc, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  const std::string prefix = command.empty() ? "ecrf: error: " : "ecrf " + command + ": error: ";
  EXPECT_EQ(r.err.rfind(prefix, 0), 0u) << r.err;
  EXPECT_NE(r.err.find(expected), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST(Cli, RenderHelpShowsFlagsWithDefaults) {
  const Output r = Capture(RunRender, {"render", "--help"});
  EXPECT_EQ(r.rc, 0);
  EXPECT_TRUE(r.err.empty()) << r.err;
  for (const char* flag : {"--views", "--orbit", "-o,--out", "SCENE"}) ExpectFlag(r.out, flag);
  ExpectFlag(r.out, "--max-views", "0");
  ExpectFlag(r.out, "-W", "400");
  ExpectFlag(r.out, "-H", "400");
  ExpectFlag(r.out, "--radius", "4");
  ExpectFlag(r.out, "--elevation", "30");
  EXPECT_NE(FlagLine(r.out, "--elevation").find("DEG:FLOAT in [-90 - 90]"), std::string::npos);
  EXPECT_NE(r.out.find("in degrees"), std::string::npos);
  ExpectRenderFlags(r.out);
}

TEST(Cli, EvalHelpShowsTrainsNamesAndDefaults) {
  const Output r = Capture(RunEval, {"eval", "-h"});
  EXPECT_EQ(r.rc, 0);
  for (const char* flag : {"--data", "--scene", "--json", "SCENE"}) ExpectFlag(r.out, flag);
  ExpectFlag(r.out, "--split", "test");
  ExpectFlag(r.out, "--seed", Text(trainer::TrainOptions().seed));
  ExpectFlag(r.out, "--test-stride", "1");
  ExpectFlag(r.out, "--max-test-views", "0");
  ExpectFlag(r.out, "--eval-downscale", "1");
  ExpectFlag(r.out, "--image-scale", "1");
  // The old names are not offered (they only explain the rename when used).
  for (const char* old : {"--stride", "--downscale", "--max-views"})
    EXPECT_EQ(FlagLine(r.out, old), "") << old;
  ExpectRenderFlags(r.out);
}

TEST(Cli, OtherCommandsHelpExitsZeroWithTheirFlags) {
  struct Case {
    int (*command)(int, char**);
    std::vector<std::string> args;
    std::vector<std::string> flags;
  };
  const std::vector<Case> cases = {
      {RunInfo, {"info", "--help"}, {"SCENE", "--md5"}},
      {RunConformance, {"conformance", "--help"}, {"--write", "--check", "--retrain-builtin"}},
      {RunReport,
       {"report", "render", "--help"},
       {"REPORT", "--lambda", "--test-stride", "--max-test-views"}},
      {RunReport, {"report", "compare", "--help"}, {"REPORTS", "--label", "--json", "--plot"}},
      {RunReport, {"report", "plot", "--help"}, {"REPORT"}},
      {RunBench, {"bench", "coder", "--help"}, {"--json"}},
      {RunBench, {"bench", "idct", "--help"}, {"--json"}},
      {RunBench,
       {"bench", "mlp", "--help"},
       {"--n", "--threads", "--reps", "--chunk", "--adam", "--best"}},
      {RunBench,
       {"bench", "train", "--help"},
       {"--res", "--rays", "--reps", "--threads", "--mask", "--blob-peak"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args[0] + " " + c.args[1]);
    const Output r = Capture(c.command, c.args);
    EXPECT_EQ(r.rc, 0) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
    EXPECT_NE(r.out.find("Usage: ecrf "), std::string::npos) << r.out;
    for (const std::string& flag : c.flags) ExpectFlag(r.out, flag);
  }
  const Output report = Capture(RunReport, {"report", "render", "--help"});
  ExpectFlag(report.out, "--test-stride", "twice the sweep's test stride");
  const Output train = Capture(RunBench, {"bench", "train", "--help"});
  ExpectFlag(train.out, "--threads", "1,2");
  ExpectFlag(train.out, "--res", "128");
}

// --run times the step on a run's own model and settings (its grid, head and early stop), not
// on the synthetic blob: a real scene's grid is what the refresh and Adam pay for.
TEST(Cli, BenchTrainRunTimesTheRunsOwnModel) {
  testing_util::ScopedTempDir dir("bench_train_run");
  trainer::TensorfModel model = testing_models::DenseSmallModel();
  trainer::TrainOptions o = trainer::PresetOptions(trainer::Preset::kFast);
  trainer::ApplyRatePoint(trainer::RatePoint::kMedium, &o);
  o.early_stop = 0.25f;  // the checkpoint's model takes its render settings from the run's
  trainer::SaveModelCheckpoint(dir.path() + "/checkpoint.ckpt", model, 10, o, nullptr, nullptr, &o);
  const Output r = Capture(RunBench, {"bench", "train", "--run", dir.path(), "--threads", "1",
                                      "--reps", "1", "--rays", "256"});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("grid 16x16x16"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("early stop 0.25"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("lambda_e 3e-11"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("blob"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("qat refresh"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("against the measured peaks"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("head 0 rows"), std::string::npos) << r.out;
  const Output blob = Capture(RunBench, {"bench", "train", "--res", "24", "--threads", "1",
                                         "--reps", "1", "--rays", "256"});
  ASSERT_EQ(blob.rc, 0) << blob.err;
  EXPECT_NE(blob.out.find("blob, res 24^3, grid 24x24x24"), std::string::npos) << blob.out;
}

TEST(Cli, SelfcheckHelpDoesNotRunTheCheck) {
  const Output help = Capture(RunSelfCheck, {"selfcheck", "--help"});
  EXPECT_EQ(help.rc, 0);
  EXPECT_NE(help.out.find("Usage: ecrf selfcheck"), std::string::npos) << help.out;
  EXPECT_EQ(help.out.find("coefficient coder:"), std::string::npos) << help.out;
  EXPECT_EQ(help.out.find("selfcheck passed"), std::string::npos) << help.out;
  ExpectOneLineError(Capture(RunSelfCheck, {"selfcheck", "--fast"}), "selfcheck",
                     "unknown option '--fast'");
  ExpectOneLineError(Capture(RunSelfCheck, {"selfcheck", "now"}), "selfcheck",
                     "unexpected argument 'now'");
  const Output run = Capture(RunSelfCheck, {"selfcheck"});
  EXPECT_EQ(run.rc, 0);
  EXPECT_NE(run.out.find("selfcheck passed"), std::string::npos) << run.out;
}

TEST(Cli, UnknownFlagsAreOneLineWithTheNearestFlag) {
  ExpectOneLineError(Capture(RunEval, {"eval", kScene, "--scene", "builtin", "--test-strid", "3"}),
                     "eval", "unknown option '--test-strid' (did you mean --test-stride?)");
  ExpectOneLineError(Capture(RunEval, {"eval", kScene, "--max-test-view", "3"}), "eval",
                     "did you mean --max-test-views?");
  ExpectOneLineError(Capture(RunRender, {"render", kScene, "--orbit", "2", "-o", "/nonexistent/x",
                                         "--elevatio", "9"}),
                     "render", "unknown option '--elevatio' (did you mean --elevation?)");
  ExpectOneLineError(Capture(RunInfo, {"info", kScene, "--md"}), "info", "did you mean --md5?");
  ExpectOneLineError(Capture(RunConformance, {"conformance", "--chek", "/tmp"}), "conformance",
                     "did you mean --check?");
  ExpectOneLineError(Capture(RunReport, {"report", "render", "/tmp", "--test-strid", "2"}),
                     "report render", "did you mean --test-stride?");
  ExpectOneLineError(Capture(RunReport, {"report", "compare", "a", "b", "--jsn", "x"}),
                     "report compare", "did you mean --json?");
  ExpectOneLineError(Capture(RunBench, {"bench", "mlp", "--rep", "2"}), "bench mlp",
                     "did you mean --reps?");
  // Subcommands likewise.
  ExpectOneLineError(Capture(RunReport, {"report", "rendr"}), "report",
                     "unknown report 'rendr' (did you mean render?)");
  ExpectOneLineError(Capture(RunBench, {"bench", "idtc"}), "bench", "did you mean idct?");
}

TEST(Cli, RenamedFlagsSayTheNewName) {
  ExpectOneLineError(Capture(RunEval, {"eval", kScene, "--scene", "builtin", "--stride", "2"}),
                     "eval", "--stride is now called --test-stride");
  ExpectOneLineError(Capture(RunEval, {"eval", kScene, "--scene", "builtin", "--downscale", "2"}),
                     "eval", "--downscale is now called --eval-downscale");
  ExpectOneLineError(Capture(RunEval, {"eval", kScene, "--scene", "builtin", "--max-views", "2"}),
                     "eval", "--max-views is now called --max-test-views");
  ExpectOneLineError(Capture(RunReport, {"report", "render", "/tmp", "--stride", "2"}),
                     "report render", "--stride is now called --test-stride");
}

TEST(Cli, BadValuesAndMissingChoicesAreUsageErrors) {
  ExpectOneLineError(Capture(RunEval, {"eval", kScene, "--scene", "nowhere"}), "eval", "--scene");
  ExpectOneLineError(Capture(RunEval, {"eval", kScene}), "eval",
                     "needs --data DIR or --scene NAME");
  ExpectOneLineError(Capture(RunEval, {"eval", kScene, "--scene", "builtin", "--data", "d"}),
                     "eval", "excludes");
  ExpectOneLineError(Capture(RunEval, {"eval", kScene, "--scene", "builtin", "--test-stride", "0"}),
                     "eval", "--test-stride");
  ExpectOneLineError(Capture(RunRender, {"render", kScene, "-o", "/nonexistent/x"}), "render",
                     "needs --views FILE or --orbit N");
  ExpectOneLineError(Capture(RunRender, {"render", kScene, "--orbit", "2", "-o", "/nonexistent/x",
                                         "--step-scale", "100"}),
                     "render", "--step-scale");
  ExpectOneLineError(Capture(RunConformance, {"conformance"}), "conformance",
                     "needs --write DIR or --check DIR");
  // The decoder's 2^26-pixel image limit holds before anything is allocated: 8192 x 8193 is
  // one row over it, 100000 x 100000 would need 40 GB for the image alone.
  ExpectOneLineError(Capture(RunRender, {"render", kScene, "--orbit", "1", "-W", "8192", "-H",
                                         "8193", "-o", "/nonexistent/x"}),
                     "render", "view orbit_000 is 8192x8193 = 67117056 pixels");
  ExpectOneLineError(Capture(RunRender, {"render", kScene, "--orbit", "1", "-W", "65536", "-H",
                                         "65536", "-o", "/nonexistent/x"}),
                     "render", "at most 67108864 pixels per image");
  ExpectOneLineError(Capture(RunBench, {"bench", "train", "--threads", "1,x"}), "bench train",
                     "--threads");
}

TEST(Cli, HelpCommandIsTheCommandsHelp) {
  const std::vector<std::vector<std::string>> commands = {{"render"},
                                                          {"eval"},
                                                          {"info"},
                                                          {"selfcheck"},
                                                          {"conformance"},
                                                          {"version"},
                                                          {"report"},
                                                          {"report", "render"},
                                                          {"report", "compare"},
                                                          {"report", "plot"},
                                                          {"bench"},
                                                          {"bench", "mlp"}};
  for (const std::vector<std::string>& words : commands) {
    std::vector<std::string> help = {"ecrf", "help"}, flag = {"ecrf"};
    help.insert(help.end(), words.begin(), words.end());
    flag.insert(flag.end(), words.begin(), words.end());
    flag.push_back("--help");
    const Output a = Capture(RunEcrf, help), b = Capture(RunEcrf, flag);
    SCOPED_TRACE(b.out);
    EXPECT_EQ(a.rc, 0);
    EXPECT_EQ(b.rc, 0);
    EXPECT_EQ(a.out, b.out);
    EXPECT_FALSE(a.out.empty());
  }
  // The general usage lists every command, on stdout for `help`, on stderr (exit code 2) for
  // nothing.
  const Output usage = Capture(RunEcrf, {"ecrf", "help"});
  EXPECT_EQ(usage.rc, 0);
  EXPECT_EQ(Capture(RunEcrf, {"ecrf", "--help"}).out, usage.out);
  for (const char* command : {"version", "selfcheck", "train", "encode", "info", "render", "eval",
                              "conformance", "report", "bench"}) {
    EXPECT_NE(usage.out.find(std::string("\n  ") + command + " "), std::string::npos) << command;
  }
  const Output nothing = Capture(RunEcrf, {"ecrf"});
  EXPECT_EQ(nothing.rc, 2);
  EXPECT_EQ(nothing.err, usage.out);
  ExpectOneLineError(Capture(RunEcrf, {"ecrf", "rendr"}), "",
                     "unknown command 'rendr' (did you mean render?)");
  ExpectOneLineError(Capture(RunEcrf, {"ecrf", "help", "evl"}), "", "did you mean eval?");
}

TEST(Cli, VersionFlagsAndCommandAgree) {
  const Output version = Capture(RunEcrf, {"ecrf", "version"});
  EXPECT_EQ(version.rc, 0);
  EXPECT_NE(version.out.find(ecrf_version_string()), std::string::npos) << version.out;
  // The bitstream as major.minor, the newest this build knows (SPEC.md's header says which).
  EXPECT_NE(version.out.find("bitstream 1.0 to 1." + std::to_string(int(kVersionMinor))),
            std::string::npos)
      << version.out;
  EXPECT_EQ(Capture(RunEcrf, {"ecrf", "--version"}).out, version.out);
  EXPECT_EQ(Capture(RunEcrf, {"ecrf", "-V"}).out, version.out);
}

TEST(Cli, ErrorsWhileRunningNameTheCommand) {
  const Output r = Capture(RunEcrf, {"ecrf", "info", "/nonexistent/scene.ecrf"});
  EXPECT_EQ(r.rc, 1);
  EXPECT_EQ(r.err.rfind("ecrf info: error: /nonexistent/scene.ecrf", 0), 0u) << r.err;
}

TEST(Cli, RenderAndEvalUseEveryCoreByDefault) {
  const testing_util::ScopedTempDir tmp("ecrf_cli_test");
  const std::string dir = tmp.path();
  const int all = std::min(AllCores(), dec::kMaxRenderThreads);
  const std::string threads = "(" + std::to_string(all) + (all == 1 ? " thread" : " threads");
  const Output render = Capture(RunRender, {"render", kScene, "--orbit", "2", "-W", "16", "-H",
                                            "12", "--elevation", "-20.5", "-o", dir + "/orbit"});
  ASSERT_EQ(render.rc, 0) << render.err;
  EXPECT_NE(render.out.find(threads), std::string::npos) << render.out;
  for (const char* png : {"/orbit/orbit_000.png", "/orbit/orbit_001.png"}) {
    EXPECT_TRUE(std::ifstream(dir + png).good()) << png;
  }
  const std::string json = dir + "/eval.json";
  const Output eval = Capture(RunEval, {"eval", kScene, "--scene", "builtin", "--max-test-views",
                                        "1", "--eval-downscale", "4", "--json", json});
  ASSERT_EQ(eval.rc, 0) << eval.err;
  EXPECT_NE(eval.out.find(threads), std::string::npos) << eval.out;
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["threads"], all);
  EXPECT_EQ(j["views"], 1);
  EXPECT_EQ(j["downscale"], 4);
  EXPECT_EQ(j["held_out_scoring"], "whole views");
  // The half-image protocol for exposure: said in the line and the JSON.
  const Output fitted = Capture(RunEval, {"eval", kScene, "--scene", "builtin", "--max-test-views",
                                          "1", "--fit-exposure", "--json", json});
  ASSERT_EQ(fitted.rc, 0) << fitted.err;
  EXPECT_NE(fitted.out.find("(right halves; exposure gains fitted on the left halves)"),
            std::string::npos)
      << fitted.out;
  std::ifstream again(json);
  EXPECT_EQ(nlohmann::json::parse(again)["held_out_scoring"],
            "right halves; exposure gains fitted on the left halves");
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
