#include "tools/prepare/prepare_dataset.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tools/run_program.h"
#include "trainer/data/dataset.h"
#include "trainer/data/image_io.h"
#include "trainer/scenes/capture_scene.h"

namespace ecrf {
namespace tools {
namespace {

namespace fs = std::filesystem;

class PrepareDatasetTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("prepare_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_ / "photos");
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

std::string ErrorOf(const PrepareOptions& o) {
  try {
    PrepareDataset(o);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST_F(PrepareDatasetTest, RefusesBadInputsBeforeAnyWork) {
  PrepareOptions o;
  o.input = (dir_ / "photos").string();
  o.out_dir = (dir_ / "data").string();
  o.camera_model = "FISHEYE";
  EXPECT_NE(ErrorOf(o).find("--camera-model FISHEYE"), std::string::npos);
  o.camera_model = "OPENCV";
  o.input = (dir_ / "missing").string();
  EXPECT_NE(ErrorOf(o).find("no such file or folder"), std::string::npos);
  // An existing dataset is never overwritten.
  o.input = (dir_ / "photos").string();
  fs::create_directories(dir_ / "data");
  std::ofstream(dir_ / "data" / "transforms.json") << "{}";
  EXPECT_NE(ErrorOf(o).find("is not an empty folder"), std::string::npos);
  EXPECT_TRUE(fs::exists(dir_ / "data" / "transforms.json"));
  o.out_dir = (dir_ / "no" / "such" / "data").string();
  EXPECT_NE(ErrorOf(o).find("does not exist"), std::string::npos);
  // A missing COLMAP says how to install it.
  o.out_dir = (dir_ / "data2").string();
  o.colmap = (dir_ / "no-colmap").string();
  EXPECT_NE(ErrorOf(o).find("apt-get install colmap"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir_ / "data2"));
}

TEST_F(PrepareDatasetTest, TooFewPhotosLeaveNothingBehind) {
  const trainer::Dataset capture = trainer::MakeCaptureScene("train", 64, 48, 3, 7);
  trainer::SavePng((dir_ / "photos" / "a.png").string(), capture.views[0].rgb);
  trainer::SavePng((dir_ / "photos" / "b.png").string(), capture.views[1].rgb);
  std::ofstream(dir_ / "photos" / "notes.txt") << "not an image";
  PrepareOptions o;
  o.input = (dir_ / "photos").string();
  o.out_dir = (dir_ / "data").string();
  o.colmap = "true";  // found, never run: the photos are counted first
  EXPECT_NE(ErrorOf(o).find("2 PNG or JPEG images; structure from motion needs at least 3"),
            std::string::npos);
  for (const auto& e : fs::directory_iterator(dir_)) EXPECT_EQ(e.path().filename(), "photos");
}

// A video goes through ffmpeg at --fps: 3 s at 8 frames per second give 6 frames at 2 per
// second, the longer side scaled to --max-size. COLMAP here is `true`, which makes no
// reconstruction: the error counts the frames and names them, and nothing is left behind.
TEST_F(PrepareDatasetTest, AVideoBecomesFramesAtTheAskedRate) {
  const std::string ffmpeg = FindExecutable("ffmpeg");
  if (ffmpeg.empty()) GTEST_SKIP() << "ffmpeg not installed (apt-get install ffmpeg)";
  const trainer::Dataset capture =
      trainer::MakeCaptureScene("train", 96, 72, 28, 7);  // 24 views: 28 less every 8th
  ASSERT_EQ(capture.views.size(), 24u);
  for (int i = 0; i < 24; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "f_%03d.png", i);
    trainer::SavePng((dir_ / "photos" / name).string(), capture.views[size_t(i)].rgb);
  }
  const std::string video = (dir_ / "walk.mp4").string();
  const ProgramResult made =
      RunProgram({ffmpeg, "-nostdin", "-v", "error", "-framerate", "8", "-i",
                  (dir_ / "photos" / "f_%03d.png").string(), "-pix_fmt", "yuv420p", video});
  ASSERT_TRUE(made.Succeeded()) << made.error_tail;
  PrepareOptions o;
  o.input = video;
  o.out_dir = (dir_ / "data").string();
  o.max_size = 64;
  o.colmap = "true";
  const std::string error = ErrorOf(o);
  EXPECT_NE(error.find("COLMAP posed 0 of 6 frames (0 reconstructions"), std::string::npos)
      << error;
  EXPECT_NE(error.find("frame_00001.jpg, frame_00002.jpg"), std::string::npos) << error;
  for (const auto& e : fs::directory_iterator(dir_)) {
    EXPECT_TRUE(e.path().filename() == "photos" || e.path().filename() == "walk.mp4") << e.path();
  }
  o.fps = 4;
  EXPECT_NE(ErrorOf(o).find("posed 0 of 12 frames"), std::string::npos);
}

// The procedural capture (a still life in a textured room, a hand-held loop, a distorting lens)
// rendered to photos: COLMAP poses every one, and the poses match the true ones up to the
// similarity structure from motion cannot know.
TEST_F(PrepareDatasetTest, PosesEveryPhotoOfARenderedCapture) {
  if (FindExecutable("colmap").empty())
    GTEST_SKIP() << "colmap not installed (apt-get install colmap)";
  constexpr int kWidth = 320, kHeight = 240, kFrames = 48;
  std::vector<trainer::Camera> truth(kFrames);
  for (const char* split : {"train", "test"}) {
    const trainer::Dataset capture = trainer::MakeCaptureScene(split, kWidth, kHeight, kFrames, 7);
    for (const trainer::View& v : capture.views) {
      const std::string name = v.name.substr(v.name.find('/') + 1);  // frame_NNN
      truth[size_t(std::stoi(name.substr(6)))] = v.camera;
      trainer::SavePng((dir_ / "photos" / (name + ".png")).string(), v.rgb);
    }
  }
  PrepareOptions o;
  o.input = (dir_ / "photos").string();
  o.out_dir = (dir_ / "data").string();
  // One thread: COLMAP's multi-threaded mapper is not deterministic, and under a loaded machine
  // (ctest -j2) it once split this capture into two reconstructions (37 of 48 frames posed).
  o.threads = 1;
  const PrepareResult r = PrepareDataset(o);
  EXPECT_EQ(r.frames, kFrames);
  EXPECT_EQ(r.registered, kFrames) << r.unregistered.size() << " without a pose";
  EXPECT_EQ(r.models, 1);
  ASSERT_TRUE(fs::exists(dir_ / "data" / "transforms.json"));
  // Nothing but the dataset: no temporary folder left beside it.
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir_)) entries += e.path().filename() != "photos";
  EXPECT_EQ(entries, 1);

  std::vector<trainer::ViewSource> views;
  for (const char* split : {"train", "test"}) {
    const trainer::DatasetManifest m =
        trainer::ReadDatasetManifest((dir_ / "data").string(), split, 1);
    views.insert(views.end(), m.views.begin(), m.views.end());
  }
  ASSERT_EQ(int(views.size()), kFrames);
  Eigen::Matrix3Xd found(3, kFrames), known(3, kFrames);
  for (int i = 0; i < kFrames; ++i) {
    const trainer::ViewSource& v = views[size_t(i)];
    const trainer::Camera& t = truth[size_t(std::stoi(v.name.substr(v.name.size() - 3)))];
    for (int a = 0; a < 3; ++a) {
      found(a, i) = v.camera.c2w[a][3];
      known(a, i) = t.c2w[a][3];
    }
    // The focal length within what COLMAP reaches here: 0.97-1.01 of the true over runs, with
    // the principal point held at the centre (the capture's is 10 px off it). k1 varied from
    // -0.09 to -0.17 (true -0.12) between runs, too loose to check; the unit tests check that
    // it reaches the json.
    EXPECT_NEAR(v.camera.fx / t.fx, 1.0, 0.1);
  }
  const Eigen::Matrix4d sim = Eigen::umeyama(found, known, true);
  const Eigen::Matrix3Xd aligned =
      (sim.topLeftCorner<3, 3>() * found).colwise() + sim.topRightCorner<3, 1>();
  const double rms = std::sqrt((aligned - known).colwise().squaredNorm().mean());
  const double spread =
      std::sqrt((known.colwise() - known.rowwise().mean()).colwise().squaredNorm().mean());
  std::printf(
      "poses: centres %.2f %% rms of the capture's spread; fx %.4f of the true, k1 %.4f "
      "(true %.4f), cx %.2f (true %.2f)\n",
      100 * rms / spread, views[0].camera.fx / truth[0].fx, views[0].camera.k1, truth[0].k1,
      views[0].camera.cx, truth[0].cx);
  // Measured 1.5-3.5 % over four runs on the unworn capture's images and 0.51 % on the worn
  // one's (COLMAP's RANSAC is not repeatable); a wrong convention or normalisation is off by the
  // whole capture.
  EXPECT_LT(rms / spread, 0.1) << "camera centres off by " << rms << " m (rms) in a " << spread
                               << " m capture";
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
