#include "trainer/data/dataset.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/common/error_of.h"
#include "trainer/data/camera.h"
#include "trainer/data/image_io.h"

namespace ecrf::trainer {
namespace {

using testing_errors::Contains;
using testing_errors::ErrorOf;

namespace fs = std::filesystem;
using nlohmann::json;

constexpr double kAngleX = 0.6911112070083618;  // chair's camera_angle_x

json Translation(double x, double y, double z) {
  return json::array({json::array({1, 0, 0, x}), json::array({0, 1, 0, y}),
                      json::array({0, 0, 1, z}), json::array({0, 0, 0, 1})});
}

class DatasetTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("ecrf_dataset_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Dir() const { return dir_.string(); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  void WriteJson(const std::string& name, const json& value) const {
    std::ofstream(dir_ / name) << value.dump(2);
  }

  // An RGBA image whose left half is transparent and right half opaque `shade` red.
  void WriteRgba(const std::string& name, int width, int height, float shade) const {
    fs::create_directories((dir_ / name).parent_path());
    Image image = MakeImage(width, height, 4);
    for (int y = 0; y < height; ++y) {
      for (int x = width / 2; x < width; ++x) {
        image.at(x, y, 0) = shade;
        image.at(x, y, 3) = 1.0f;
      }
    }
    SavePng(Path(name), image);
  }

  // Blender layout with three 8x6 frames; frame 2's file_path carries its extension.
  json WriteBlender() const {
    json root;
    root["camera_angle_x"] = kAngleX;
    root["frames"] = json::array();
    for (int i = 0; i < 3; ++i) {
      const std::string stem = "train/r_" + std::to_string(i);
      WriteRgba(stem + ".png", 8, 6, 0.2f * (i + 1));
      json frame;
      frame["file_path"] = "./" + stem + (i == 2 ? ".png" : "");
      frame["transform_matrix"] = Translation(i, 0, 4);
      root["frames"].push_back(frame);
    }
    WriteJson("transforms_train.json", root);
    return root;
  }

  fs::path dir_;
};

TEST_F(DatasetTest, LoadsBlenderLayout) {
  WriteBlender();
  const Dataset dataset = LoadDataset(Dir(), "train", 1);
  ASSERT_EQ(dataset.views.size(), 3u);
  EXPECT_TRUE(dataset.white_background);
  EXPECT_FALSE(dataset.estimated_poses);  // rendered: the cameras are exact
  EXPECT_EQ(dataset.near, 2.0);
  EXPECT_EQ(dataset.far, 6.0);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(dataset.scene_aabb[0][a], -1.5);
    EXPECT_EQ(dataset.scene_aabb[1][a], 1.5);
  }
  const View& view = dataset.views[1];
  EXPECT_EQ(view.name, "train/r_1");
  EXPECT_EQ(dataset.views[2].name, "train/r_2");
  EXPECT_EQ(view.camera.width, 8);
  EXPECT_EQ(view.camera.height, 6);
  EXPECT_DOUBLE_EQ(view.camera.fx, 0.5 * 8 / std::tan(0.5 * kAngleX));
  EXPECT_DOUBLE_EQ(view.camera.fy, view.camera.fx);
  EXPECT_EQ(view.camera.cx, 4.0);
  EXPECT_EQ(view.camera.cy, 3.0);
  EXPECT_EQ(view.camera.c2w[0][3], 1.0);
  EXPECT_EQ(view.camera.c2w[2][3], 4.0);
  EXPECT_FALSE(view.camera.HasDistortion());
  ASSERT_EQ(view.rgb.channels, 3);
  // Transparent left half composited to white, opaque right half keeps its colour.
  EXPECT_EQ(view.rgb.at(0, 0, 1), 1.0f);
  EXPECT_NEAR(view.rgb.at(7, 5, 0), 0.4f, 1.0 / 255);
  EXPECT_EQ(view.rgb.at(7, 5, 1), 0.0f);
}

TEST_F(DatasetTest, DownscalesImagesAndIntrinsicsTogether) {
  WriteBlender();
  const Dataset full = LoadDataset(Dir(), "train", 1);
  const Dataset half = LoadDataset(Dir(), "train", 2);
  const View& view = half.views[0];
  EXPECT_EQ(view.rgb.width, 4);
  EXPECT_EQ(view.rgb.height, 3);
  EXPECT_EQ(view.camera.width, 4);
  EXPECT_DOUBLE_EQ(view.camera.fx, full.views[0].camera.fx / 2);
  EXPECT_DOUBLE_EQ(view.camera.cx, 2.0);
  // The same world ray through a half-resolution pixel centre and the matching full-res point.
  float o1[3], d1[3], o2[3], d2[3];
  GenerateRay(view.camera, 1, 2, o1, d1);
  GenerateRay(full.views[0].camera, 2.5, 4.5, o2, d2);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(d1[a], d2[a], 1e-6);
  EXPECT_THROW(LoadDataset(Dir(), "train", 0), std::runtime_error);
}

TEST_F(DatasetTest, ManifestDoesNotDecodeImages) {
  WriteBlender();
  const DatasetManifest manifest = ReadDatasetManifest(Dir(), "train");
  ASSERT_EQ(manifest.views.size(), 3u);
  EXPECT_EQ(manifest.views[0].image_path, (dir_ / "train/r_0.png").string());
  EXPECT_EQ(manifest.views[2].image_path, (dir_ / "train/r_2.png").string());
  const std::vector<View> views = LoadViews(manifest.views, 1);
  EXPECT_EQ(views.size(), 3u);
}

TEST_F(DatasetTest, BlenderErrorsNameFileFrameAndField) {
  json root = WriteBlender();
  const std::string file = Path("transforms_train.json");
  auto error_for = [&](const json& broken) {
    WriteJson("transforms_train.json", broken);
    return ErrorOf([&] { LoadDataset(Dir(), "train", 1); });
  };

  json no_matrix = root;
  no_matrix["frames"][1].erase("transform_matrix");
  std::string error = error_for(no_matrix);
  EXPECT_TRUE(Contains(error, file) && Contains(error, "frame 1") &&
              Contains(error, "'transform_matrix'"))
      << error;

  json bad_matrix = root;
  bad_matrix["frames"][2]["transform_matrix"] = json::array({json::array({1, 2, 3})});
  error = error_for(bad_matrix);
  EXPECT_TRUE(Contains(error, "frame 2") && Contains(error, "not a 4x4 array")) << error;

  json no_focal = root;
  no_focal.erase("camera_angle_x");
  error = error_for(no_focal);
  EXPECT_TRUE(Contains(error, file) && Contains(error, "camera_angle_x")) << error;

  json bad_type = root;
  bad_type["camera_angle_x"] = "wide";
  error = error_for(bad_type);
  EXPECT_TRUE(Contains(error, "'camera_angle_x' must be a number")) << error;

  json no_path = root;
  no_path["frames"][0].erase("file_path");
  EXPECT_TRUE(Contains(error_for(no_path), "frame 0: missing 'file_path'"));

  json no_frames = root;
  no_frames.erase("frames");
  EXPECT_TRUE(Contains(error_for(no_frames), "missing 'frames'"));

  std::ofstream(file) << "{\"frames\": [";
  error = ErrorOf([&] { LoadDataset(Dir(), "train", 1); });
  EXPECT_TRUE(Contains(error, file) && Contains(error, "invalid JSON")) << error;

  // A number beyond binary64 is a JSON error of that file, not an anonymous exception.
  std::ofstream(file) << "{\"camera_angle_x\": 1e999, \"frames\": []}";
  error = ErrorOf([&] { LoadDataset(Dir(), "train", 1); });
  EXPECT_TRUE(Contains(error, file) && Contains(error, "invalid JSON")) << error;
}

// The dataset's pixel budget is checked from the cameras before any image is read (these
// images do not even exist): 600 views of 2000x1000 are 1.2 G pixels.
TEST(DatasetBudget, TooManyPixelsAreRefusedBeforeLoading) {
  std::vector<ViewSource> sources(600);
  for (ViewSource& source : sources) {
    source.camera.width = 2000;
    source.camera.height = 1000;
    source.image_path = "/nonexistent/view.png";
  }
  const std::string error = ErrorOf([&] { LoadViews(sources, 1); });
  EXPECT_TRUE(Contains(error, "600 views of 2000x1000") && Contains(error, "1200000000 pixels") &&
              Contains(error, "use a larger --downscale"))
      << error;
  // Downscaled by 2 they fit the budget, and loading goes on to the (missing) image.
  EXPECT_TRUE(Contains(ErrorOf([&] { LoadViews(sources, 2); }), "/nonexistent/view.png"));
}

// Degenerate poses train NaN models (rays of NaN direction), so the loader refuses them.
TEST_F(DatasetTest, RefusesDegenerateAndMirroredPoses) {
  json root = WriteBlender();
  const std::string file = Path("transforms_train.json");
  auto error_for = [&](const json& broken) {
    WriteJson("transforms_train.json", broken);
    return ErrorOf([&] { LoadDataset(Dir(), "train", 1); });
  };
  const json zero = json::array({json::array({0, 0, 0, 0}), json::array({0, 0, 0, 0}),
                                 json::array({0, 0, 0, 0}), json::array({0, 0, 0, 1})});
  json zeros = root;
  zeros["frames"][1]["transform_matrix"] = zero;
  std::string error = error_for(zeros);
  EXPECT_TRUE(Contains(error, file) && Contains(error, "frame 1 ('") &&
              Contains(error, "not orthonormal"))
      << error;

  json scaled = root;  // a rotation scaled by 1.01 is not a rotation
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c)
      scaled["frames"][0]["transform_matrix"][r][c] = (r == c) ? 1.01 : 0.0;
  }
  EXPECT_TRUE(Contains(error_for(scaled), "not orthonormal"));

  json mirrored = root;
  mirrored["frames"][2]["transform_matrix"][0][0] = -1.0;
  error = error_for(mirrored);
  EXPECT_TRUE(Contains(error, "frame 2") && Contains(error, "reflection")) << error;

  // Intrinsics out of any lens's range are refused before training, with the value.
  json intrinsics = root;
  intrinsics["camera_angle_x"] = 3.141592653589793;  // 180 degrees: no ray inside the scene
  error = error_for(intrinsics);
  EXPECT_TRUE(Contains(error, file) && Contains(error, "intrinsics: the focal length") &&
              Contains(error, "field of view"))
      << error;
  intrinsics = root;
  intrinsics.erase("camera_angle_x");
  intrinsics["fl_x"] = 1e-300;
  EXPECT_TRUE(Contains(error_for(intrinsics), "the focal length 1e-300 px"))
      << error_for(intrinsics);
  intrinsics = root;
  intrinsics["cx"] = 1e308;
  EXPECT_TRUE(Contains(error_for(intrinsics), "the principal point")) << error_for(intrinsics);
  intrinsics = root;
  intrinsics["k1"] = 1e30;
  EXPECT_TRUE(Contains(error_for(intrinsics), "k1 = 1e+30 is not a lens")) << error_for(intrinsics);

  json far = root;  // finite, but no single-precision ray can start there
  far["frames"][1]["transform_matrix"][0][3] = 1e300;
  error = error_for(far);
  EXPECT_TRUE(Contains(error, "frame 1") && Contains(error, "the camera position is 1e+300"))
      << error;

  json slightly_off = root;  // rounding in written poses stays accepted
  slightly_off["frames"][0]["transform_matrix"][0][0] = 1.0 + 2e-5;
  WriteJson("transforms_train.json", slightly_off);
  EXPECT_NO_THROW(LoadDataset(Dir(), "train", 1));
}

// A FIFO where an image or the camera file should be: refused at once, naming it, instead of
// blocking in open() until something writes to it (#60).
TEST_F(DatasetTest, FifoImageOrCameraFileIsRefusedWithoutBlocking) {
  const json root = WriteBlender();
  const std::string image = (dir_ / "train/r_1.png").string();
  fs::remove(image);
  ASSERT_EQ(mkfifo(image.c_str(), 0644), 0);
  std::string error = ErrorOf([&] { LoadDataset(Dir(), "train", 1); });
  EXPECT_TRUE(Contains(error, image) && Contains(error, "is a FIFO (named pipe)")) << error;
  const std::string cameras = Path("transforms_train.json");
  fs::remove(cameras);
  ASSERT_EQ(mkfifo(cameras.c_str(), 0644), 0);
  error = ErrorOf([&] { LoadDataset(Dir(), "train", 1); });
  EXPECT_TRUE(Contains(error, cameras) && Contains(error, "is a FIFO (named pipe)")) << error;
  fs::remove(image);
  fs::create_directory(image);
  fs::remove(cameras);
  WriteJson("transforms_train.json", root);  // the camera file again; the image a directory
  error = ErrorOf([&] { LoadDataset(Dir(), "train", 1); });
  EXPECT_TRUE(Contains(error, image) && Contains(error, "is a directory")) << error;
}

TEST_F(DatasetTest, MissingBlenderImageIsAnError) {
  WriteBlender();
  fs::remove(dir_ / "train/r_1.png");
  const std::string error = ErrorOf([&] { LoadDataset(Dir(), "train", 1); });
  EXPECT_TRUE(Contains(error, (dir_ / "train/r_1.png").string())) << error;
}

TEST_F(DatasetTest, ReportsMissingDirectoryFileAndSplit) {
  EXPECT_TRUE(
      Contains(ErrorOf([&] { LoadDataset(Path("nothing"), "train", 1); }), "no such directory"));
  WriteJson("a_file", json::object());
  EXPECT_TRUE(
      Contains(ErrorOf([&] { LoadDataset(Path("a_file"), "train", 1); }), "not a directory"));
  std::string error = ErrorOf([&] { LoadDataset(Dir(), "train", 1); });
  EXPECT_TRUE(Contains(error, "transforms_train.json nor transforms.json")) << error;
  EXPECT_FALSE(Contains(error, "ecrf prepare")) << error;
  // A folder of photos without poses: the message points to `ecrf prepare`.
  WriteRgba("IMG_0001.JPG.png", 4, 4, 0.5f);
  fs::rename(dir_ / "IMG_0001.JPG.png", dir_ / "IMG_0001.JPG");
  error = ErrorOf([&] { LoadDataset(Dir(), "train", 1); });
  EXPECT_TRUE(Contains(error, "for photos without camera poses: ecrf prepare " + Dir())) << error;
  fs::remove(dir_ / "IMG_0001.JPG");
  WriteBlender();
  EXPECT_TRUE(
      Contains(ErrorOf([&] { LoadDataset(Dir(), "training", 1); }), "unknown split 'training'"));
}

// Instant-NGP layout: ten JPEG frames written out of order, shared intrinsics with distortion,
// one frame overriding its focal length, one frame's image missing.
class NgpDatasetTest : public DatasetTest {
 protected:
  void WriteNgp(bool drop_image_3) {
    json root;
    root["fl_x"] = 20.0;
    root["fl_y"] = 21.0;
    root["cx"] = 7.5;
    root["cy"] = 5.0;
    root["w"] = 16;
    root["h"] = 12;
    root["k1"] = -0.1;
    root["k2"] = 0.01;
    root["p1"] = 0.001;
    root["p2"] = -0.002;
    root["aabb_scale"] = 2;
    root["frames"] = json::array();
    for (int i = 9; i >= 0; --i) {
      const std::string name = "images/frame_" + std::to_string(i) + ".jpg";
      if (!(drop_image_3 && i == 3)) {
        fs::create_directories(dir_ / "images");
        // SavePng output under a .jpg name is fine: the loader sniffs the format.
        SavePng(Path(name), MakeImage(16, 12, 3, 0.5f));
      }
      json frame;
      frame["file_path"] = name;
      frame["transform_matrix"] = Translation(0, 0, 4 + i);
      if (i == 5) frame["fl_x"] = 30.0;
      root["frames"].push_back(frame);
    }
    WriteJson("transforms.json", root);
  }
};

TEST_F(NgpDatasetTest, SplitsEveryEighthFrameForTest) {
  WriteNgp(false);
  const Dataset train = LoadDataset(Dir(), "train", 1);
  const Dataset test = LoadDataset(Dir(), "test", 1);
  ASSERT_EQ(test.views.size(), 2u);
  ASSERT_EQ(train.views.size(), 8u);
  EXPECT_EQ(test.views[0].name, "images/frame_0");
  EXPECT_EQ(test.views[1].name, "images/frame_8");  // sorted by path: 0 1 2 3 4 5 6 7 8 9
  EXPECT_EQ(LoadDataset(Dir(), "val", 1).views.size(), 2u);
  EXPECT_FALSE(train.white_background);  // RGB images, nothing composited
  // Instant-NGP / nerfstudio poses come from structure from motion (--refine-cameras auto).
  EXPECT_TRUE(train.estimated_poses);
  EXPECT_TRUE(test.estimated_poses);
}

TEST_F(NgpDatasetTest, ReadsIntrinsicsDistortionAndBounds) {
  WriteNgp(false);
  const DatasetManifest manifest = ReadDatasetManifest(Dir(), "train");
  const ViewSource* five = nullptr;
  for (const ViewSource& view : manifest.views) {
    if (view.name == "images/frame_5") five = &view;
  }
  ASSERT_NE(five, nullptr);
  const Camera& camera = manifest.views[0].camera;
  EXPECT_EQ(camera.width, 16);
  EXPECT_EQ(camera.height, 12);
  EXPECT_EQ(camera.fx, 20.0);
  EXPECT_EQ(camera.fy, 21.0);
  EXPECT_EQ(camera.cx, 7.5);
  EXPECT_EQ(camera.cy, 5.0);
  EXPECT_EQ(camera.k1, -0.1);
  EXPECT_EQ(camera.k2, 0.01);
  EXPECT_EQ(camera.p1, 0.001);
  EXPECT_EQ(camera.p2, -0.002);
  EXPECT_EQ(five->camera.fx, 30.0);  // per-frame override
  EXPECT_EQ(five->camera.fy, 21.0);
  // aabb_scale 2 with the default NGP scale 0.33: half extent 0.5 * 2 / 0.33 about the origin.
  const double half = 0.5 * 2 / 0.33;
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(manifest.scene_aabb[0][a], -half, 1e-12);
    EXPECT_NEAR(manifest.scene_aabb[1][a], half, 1e-12);
  }
  // Cameras at z = 4..13 on the axis: nearest is 4 - half from the box top, farthest corner
  // from z = 13 is sqrt(2 half^2 + (13 + half)^2); computed over all frames, not the split.
  EXPECT_NEAR(manifest.near, 4 - half, 1e-9);
  EXPECT_NEAR(manifest.far, std::sqrt(2 * half * half + (13 + half) * (13 + half)), 1e-9);
  EXPECT_EQ(ReadDatasetManifest(Dir(), "test").near, manifest.near);
}

TEST_F(NgpDatasetTest, CameraInsideTheBoxKeepsNearPositive) {
  WriteJson(
      "transforms.json",
      {{"fl_x", 10},
       {"w", 4},
       {"h", 4},
       {"frames",
        json::array({{{"file_path", "a.png"}, {"transform_matrix", Translation(0, 0, 0)}}})}});
  SavePng(Path("a.png"), MakeImage(4, 4, 3));
  const DatasetManifest manifest = ReadDatasetManifest(Dir(), "test");
  const double diagonal = std::sqrt(3.0) / 0.33;
  EXPECT_NEAR(manifest.near, 0.01 * diagonal, 1e-12);
  EXPECT_NEAR(manifest.far, diagonal / 2, 1e-12);
}

TEST_F(NgpDatasetTest, SkipsFramesWithMissingImages) {
  WriteNgp(true);
  ::testing::internal::CaptureStderr();
  const Dataset train = LoadDataset(Dir(), "train", 1);
  const std::string warnings = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(train.views.size(), 7u);
  EXPECT_TRUE(Contains(warnings, "frame_3.jpg")) << warnings;
  for (const View& view : train.views) EXPECT_NE(view.name, "images/frame_3");
}

// A frame whose image is a symlink loop is not a missing image to skip: the cause is named.
TEST_F(NgpDatasetTest, AnImageThatCannotBeFollowedIsNamedWithItsCause) {
  WriteNgp(true);
  const fs::path loop = dir_ / "images/frame_3.jpg";
  fs::create_symlink(loop.filename(), loop);  // points at itself
  const std::string error = ErrorOf([&] { LoadDataset(Dir(), "train", 1); });
  EXPECT_TRUE(Contains(error, loop.string()) && Contains(error, "symbolic links")) << error;
}

// Frames that name one file decode it once and share its pixels, each with its own camera.
TEST_F(DatasetTest, FramesNamingOneImageShareItsPixels) {
  WriteRgba("train/r_0.png", 8, 6, 0.4f);
  json root;
  root["camera_angle_x"] = kAngleX;
  for (int i = 0; i < 5; ++i) {
    json frame;
    frame["file_path"] = i % 2 ? "./train/r_0" : "train/../train/r_0.png";
    frame["transform_matrix"] = Translation(i, 0, 4);
    root["frames"].push_back(frame);
  }
  WriteJson("transforms_train.json", root);
  const Dataset d = LoadDataset(Dir(), "train", 1);
  ASSERT_EQ(d.views.size(), 5u);
  for (const View& v : d.views) {
    EXPECT_EQ(v.rgb.pixels, d.views[0].rgb.pixels);
    EXPECT_EQ(v.rgb.width, 8);
  }
  EXPECT_EQ(d.views[3].camera.c2w[0][3], 3.0);
  EXPECT_EQ(d.views[2].camera.c2w[0][3], 2.0);
}

TEST_F(NgpDatasetTest, NoRemainingFrameIsAnError) {
  WriteNgp(false);
  fs::remove(dir_ / "images/frame_0.jpg");
  fs::remove(dir_ / "images/frame_8.jpg");
  ::testing::internal::CaptureStderr();
  const std::string error = ErrorOf([&] { LoadDataset(Dir(), "test", 1); });
  ::testing::internal::GetCapturedStderr();
  EXPECT_TRUE(Contains(error, Path("transforms.json")) && Contains(error, "2 skipped")) << error;
}

TEST_F(NgpDatasetTest, RejectsUnsupportedCameraModels) {
  WriteJson("transforms.json", {{"camera_model", "OPENCV_FISHEYE"},
                                {"fl_x", 10},
                                {"w", 4},
                                {"h", 4},
                                {"frames", json::array()}});
  EXPECT_TRUE(Contains(ErrorOf([&] { LoadDataset(Dir(), "train", 1); }), "OPENCV_FISHEYE"));
  WriteJson("transforms.json", {{"k3", 0.1}, {"frames", json::array()}});
  EXPECT_TRUE(Contains(ErrorOf([&] { LoadDataset(Dir(), "train", 1); }), "'k3' is not supported"));
}

}  // namespace
}  // namespace ecrf::trainer
