// `ecrf train` finds an unusable output before it loads data or trains, and a run that fails
// early leaves no empty directory behind.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tests/common/invoke.h"
#include "tests/common/scoped_temp_dir.h"
#include "tools/cli_args.h"
#include "tools/commands.h"
#include "tools/encode_run.h"
#include "tools/train_run.h"
#include "trainer/data/file_io.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {
namespace {

using testing_cli::Invoke;

std::string ErrorOf(std::vector<std::string> args) {
  try {
    Invoke(RunTrain, std::move(args));
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

class TrainOutputTest : public ::testing::Test {
 protected:
  const testing_util::ScopedTempDir tmp_{"ecrf_train_output"};
  const std::string root_ = tmp_.path();
};

TEST_F(TrainOutputTest, FailedRunLeavesNoEmptyDirectories) {
  const std::string out = root_ + "/new/run";
  const std::string error = ErrorOf({"train", "--data", root_ + "/no_such_scene", "-o", out});
  EXPECT_NE(error.find("no_such_scene"), std::string::npos) << error;
  EXPECT_FALSE(FileExists(root_ + "/new")) << "the failed run left " << root_ << "/new behind";
}

TEST_F(TrainOutputTest, OutputBelowAFileFailsBeforeLoadingData) {
  const std::string file = root_ + "/file";
  std::fclose(std::fopen(file.c_str(), "wb"));
  // The data directory does not exist either: the output is checked first.
  const std::string error =
      ErrorOf({"train", "--data", root_ + "/no_such_scene", "-o", file + "/run"});
  EXPECT_NE(error.find("cannot create directory"), std::string::npos) << error;
}

TEST_F(TrainOutputTest, ReadOnlyOutputFailsBeforeLoadingData) {
  if (geteuid() == 0) GTEST_SKIP() << "root writes into read-only directories";
  const std::string dir = root_ + "/read_only";
  ASSERT_EQ(mkdir(dir.c_str(), 0555), 0);
  const std::string error = ErrorOf({"train", "--data", root_ + "/no_such_scene", "-o", dir});
  EXPECT_NE(error.find("cannot write into this directory"), std::string::npos) << error;
  chmod(dir.c_str(), 0755);
}

// --resume where nothing can be resumed says what is there and what to do instead.
TEST_F(TrainOutputTest, ResumeWithoutCheckpointSaysWhatIsThereAndWhatToDo) {
  const std::string fresh = root_ + "/fresh";
  const std::string error = ErrorOf({"train", "--scene", "builtin", "--resume", "-o", fresh});
  EXPECT_NE(error.find("--resume: " + fresh +
                       " has no checkpoint.ckpt to continue from (it holds "
                       "no run): start the run without --resume"),
            std::string::npos)
      << error;
  EXPECT_FALSE(FileExists(fresh));
  // A run stopped before its first checkpoint leaves its config.json.
  const std::string started = root_ + "/started";
  ASSERT_EQ(mkdir(started.c_str(), 0755), 0);
  trainer::WriteFileAtomically(started + "/config.json", std::string("{}"));
  const std::string again = ErrorOf({"train", "--scene", "builtin", "--resume", "-o", started});
  EXPECT_NE(again.find("(it holds config.json: the run stopped before its first checkpoint): "
                       "start it again with --overwrite"),
            std::string::npos)
      << again;
}

// A directory that holds a run is not overwritten silently: refused before the data is read
// (the data directory does not exist), naming what is there and the two ways on; its files stay.
TEST_F(TrainOutputTest, ExistingRunIsRefusedUnlessResumedOrOverwritten) {
  const std::string dir = root_ + "/run";
  ASSERT_EQ(mkdir(dir.c_str(), 0755), 0);
  for (const char* name : {"scene.ecrf", "metrics.json"}) {
    trainer::WriteFileAtomically(dir + "/" + name, std::string("kept"));
  }
  const std::string error = ErrorOf({"train", "--data", root_ + "/no_such_scene", "-o", dir});
  EXPECT_NE(error.find(dir + " already holds a run (scene.ecrf, metrics.json): --resume "
                             "continues it, --overwrite replaces it"),
            std::string::npos)
      << error;
  EXPECT_EQ(trainer::ReadWholeFile(dir + "/scene.ecrf").size(), 4u);
  // With --overwrite the run starts (and here fails on the missing data, as any new run would).
  const std::string overwrite =
      ErrorOf({"train", "--data", root_ + "/no_such_scene", "--overwrite", "-o", dir});
  EXPECT_EQ(overwrite.find("already holds a run"), std::string::npos) << overwrite;
  EXPECT_NE(overwrite.find("no_such_scene"), std::string::npos) << overwrite;
}

// --eval-downscale: a short run scored at half size records it, with the renderer's samples per
// ray.
// A disk that fills up (here a 1 MB limit on the size of any file the process writes): the final
// checkpoint (9 MB) cannot be written, but the run's file (about 120 KB) and metrics.json still
// are, from the model in memory. Before, the run ended with the checkpoint's error and no file.
TEST_F(TrainOutputTest, AFullDiskStillGetsTheRunsFile) {
  const std::string out = root_ + "/run";
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::signal(SIGXFSZ, SIG_IGN);  // a write past the limit fails with EFBIG instead
    const rlimit limit = {1 << 20, 1 << 20};
    if (setrlimit(RLIMIT_FSIZE, &limit) != 0) _exit(3);
    int rc = 4;
    try {
      rc = Invoke(RunTrain,
                  {"train", "--scene", "builtin", "--iters", "40", "--builtin-size", "32",
                   "--builtin-views", "16", "--max-test-views", "1", "--threads", "1", "-o", out});
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s\n", e.what());
    }
    _exit(rc);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_TRUE(FileExists(out + "/scene.ecrf"));
  EXPECT_TRUE(FileExists(out + "/metrics.json"));
  EXPECT_FALSE(FileExists(out + "/checkpoint.ckpt"));  // and no temporary left behind either
  for (const auto& e : std::filesystem::directory_iterator(out)) {
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
  }
}

TEST_F(TrainOutputTest, EvalDownscaleIsRecordedWithSamplesPerRay) {
  const std::string out = root_ + "/run";
  Invoke(RunTrain,
         {"train", "--scene", "builtin", "--iters", "160", "--batch", "512", "--final-grid", "48",
          "--lambda-e", "0", "--eval-downscale", "2", "--max-test-views", "2", "-o", out});
  std::FILE* f = std::fopen((out + "/metrics.json").c_str(), "rb");
  ASSERT_NE(f, nullptr);
  std::string text;
  char buffer[4096];
  for (size_t n; (n = std::fread(buffer, 1, sizeof(buffer), f)) > 0;) text.append(buffer, n);
  std::fclose(f);
  const nlohmann::json m = nlohmann::json::parse(text);
  EXPECT_EQ(m["eval_downscale"], 2);
  EXPECT_EQ(m["test_views"], 2);
  EXPECT_GT(m["decoded_samples_per_ray"].get<double>(), 1.0);
  EXPECT_GT(m["decoded_samples_per_ray"].get<double>(),
            m["decoded_mlp_samples_per_ray"].get<double>());
  EXPECT_GT(m["decoded_test_psnr"].get<double>(), 10.0);
  testing::internal::CaptureStderr();
  EXPECT_EQ(Invoke(RunTrain,
                   {"train", "--scene", "builtin", "--eval-downscale", "0", "-o", root_ + "/bad"}),
            2);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("--eval-downscale"), std::string::npos);
}

std::string ReadAll(const std::string& path) {
  std::string text;
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    char buffer[4096];
    for (size_t n; (n = std::fread(buffer, 1, sizeof(buffer), f)) > 0;) text.append(buffer, n);
    std::fclose(f);
  }
  return text;
}

// A run with a camera warm-up (RUN/warmup/) resumes to the file the uninterrupted run writes,
// byte for byte: stopped in its main pass; then with the main pass's checkpoint gone, as when a
// run is killed before its first one (the finished warm-up is reloaded, the main pass starts
// afresh); then from the main pass's checkpoint.
TEST_F(TrainOutputTest, RunWithCameraWarmUpResumesToTheSameFile) {
  // One refinement round per pass on 16 views: the rounds' cost grows with the views, and the
  // test is about state, not quality.
  // clang-format off
  const std::vector<std::string> flags = {
      "train", "--scene", "builtin", "--builtin-views", "16", "--iters", "160", "--batch", "512",
      "--final-grid", "32",
      "--lambda-e", "0", "--max-test-views", "1", "--refine-cameras", "on",
      "--refine-cameras-every", "100", "--camera-warmup-iters", "80", "--checkpoint-every", "40"};
  // clang-format on
  auto with = [&flags](std::vector<std::string> more) {
    std::vector<std::string> all = flags;
    all.insert(all.end(), more.begin(), more.end());
    return all;
  };
  const std::string whole = root_ + "/whole", parts = root_ + "/parts";
  ASSERT_EQ(Invoke(RunTrain, with({"-o", whole})), 0);
  const std::string file = ReadAll(whole + "/scene.ecrf");
  ASSERT_FALSE(file.empty());
  EXPECT_TRUE(FileExists(whole + "/warmup/checkpoint.ckpt"));
  const nlohmann::json metrics = nlohmann::json::parse(ReadAll(whole + "/metrics.json"));
  EXPECT_EQ(metrics["camera_warmup_iters"], 80);
  EXPECT_EQ(metrics["held_out_scoring"], "right halves; cameras aligned on the left halves");
  EXPECT_TRUE(metrics.contains("decoded_test_psnr_as_given"));

  ASSERT_EQ(Invoke(RunTrain, with({"--stop-after", "100", "-o", parts})), 0);
  EXPECT_FALSE(FileExists(parts + "/scene.ecrf"));
  ASSERT_EQ(std::remove((parts + "/checkpoint.ckpt").c_str()), 0);
  ASSERT_EQ(Invoke(RunTrain, with({"--stop-after", "100", "--resume", "-o", parts})), 0);
  EXPECT_FALSE(FileExists(parts + "/scene.ecrf"));
  ASSERT_EQ(Invoke(RunTrain, with({"--resume", "-o", parts})), 0);
  EXPECT_TRUE(ReadAll(parts + "/scene.ecrf") == file) << "the resumed run wrote another file";
}

// A run with exposure codes (left out of the file) scores its held-out views with the half-image
// protocol, and also whole views at the file's exposure with the dataset's cameras (#59).
TEST_F(TrainOutputTest, ExposureCodesScoreRightHalvesAndWholeViewsAsGiven) {
  const std::string run = root_ + "/exposure";
  ASSERT_EQ(Invoke(RunTrain, {"train", "--scene", "builtin", "--iters", "40", "--batch", "256",
                              "--final-grid", "32", "--max-test-views", "1", "--exposure-codes",
                              "on", "-o", run}),
            0);
  const nlohmann::json m = nlohmann::json::parse(ReadAll(run + "/metrics.json"));
  EXPECT_EQ(m["held_out_scoring"], "right halves; exposure gains fitted on the left halves");
  ASSERT_TRUE(m.contains("decoded_test_psnr_as_given"));
  EXPECT_GT(m["decoded_test_psnr_as_given"].get<double>(), 5.0);  // 40 iterations: ~7.5 dB
  EXPECT_NE(m["decoded_test_psnr_as_given"], m["decoded_test_psnr"]);
  // Without them (an object scene, no refined cameras) whole views, one figure.
  const std::string plain = root_ + "/plain";
  ASSERT_EQ(Invoke(RunTrain, {"train", "--scene", "builtin", "--iters", "40", "--batch", "256",
                              "--final-grid", "32", "--max-test-views", "1", "-o", plain}),
            0);
  const nlohmann::json p = nlohmann::json::parse(ReadAll(plain + "/metrics.json"));
  EXPECT_EQ(p["held_out_scoring"], "whole views");
  EXPECT_FALSE(p.contains("decoded_test_psnr_as_given"));
}

// A sweep continues a point's checkpoint only when it holds the point's own settings (CanResume),
// and starts it afresh otherwise.
TEST_F(TrainOutputTest, CanResumeAStoppedRunWithItsOwnSettingsOnly) {
  const std::string run = root_ + "/stopped";
  ASSERT_EQ(Invoke(RunTrain, {"train", "--scene", "builtin", "--iters", "40", "--batch", "256",
                              "--final-grid", "32", "--max-test-views", "1", "--stop-after", "10",
                              "-o", run}),
            0);
  const trainer::CheckpointRunInfo info = trainer::ReadCheckpointRunInfo(run + "/checkpoint.ckpt");
  ASSERT_TRUE(info.has_config);
  trainer::TrainOptions o = info.config;
  o.out_dir = run;
  EXPECT_TRUE(CanResume(o));
  o.iters += 1;
  EXPECT_FALSE(CanResume(o));
  o = info.config;
  o.out_dir = root_ + "/elsewhere";
  EXPECT_FALSE(CanResume(o));
}

// A shipped file names the dataset folder, not the path on the training machine (#60), unless
// --meta-data-path asks for it.
TEST(MetaDataSource, NamesTheDatasetFolderUnlessAskedForThePath) {
  trainer::TrainOptions o;
  o.data_dir = "/home/someone/secret-project/scenes/chair/";
  EXPECT_EQ(MetaDataSource(o), "chair");
  o.data_dir = "../shared/data/nerf_synthetic_400/mic";
  EXPECT_EQ(MetaDataSource(o), "mic");
  const trainer::RateState rate;
  const nlohmann::json meta =
      nlohmann::json::parse(TrainedRunEncodeOptions(o, rate, 10, 0.f).metadata_json);
  EXPECT_EQ(meta["data"], "mic");
  EXPECT_EQ(meta.dump().find("shared"), std::string::npos) << meta.dump();
  o.meta_data_path = true;
  EXPECT_EQ(MetaDataSource(o), "../shared/data/nerf_synthetic_400/mic");
  o.meta_data_path = false;
  o.procedural_scene = trainer::ProceduralScene::kBuiltin;
  EXPECT_EQ(MetaDataSource(o), "builtin");
}

TEST(OutputDirectory, ProbesAndRemovesOnlyWhatItCreatedWhileEmpty) {
  const testing_util::ScopedTempDir tmp("ecrf_outdir");
  const std::string root = tmp.path();
  {
    OutputDirectory d(root + "/a/b");
    EXPECT_TRUE(IsDirectory(root + "/a/b"));
    EXPECT_FALSE(FileExists(root + "/a/b/.ecrf_write_probe"));
  }
  EXPECT_FALSE(FileExists(root + "/a")) << "empty directories it created stay";
  {
    OutputDirectory d(root + "/a/b");
    std::fclose(std::fopen((root + "/a/b/result").c_str(), "wb"));
  }
  EXPECT_TRUE(FileExists(root + "/a/b/result")) << "a directory with results was removed";
  {
    OutputDirectory d(root);  // existed before: never removed
  }
  EXPECT_TRUE(IsDirectory(root));
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
