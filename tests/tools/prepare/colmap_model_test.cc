#include "tools/prepare/colmap_model.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "trainer/data/dataset.h"
#include "trainer/data/image_io.h"
#include "trainer/scenes/capture_scene.h"

namespace ecrf {
namespace tools {
namespace {

namespace fs = std::filesystem;

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

// images.txt for cameras in the trainer's convention, as COLMAP writes it.
std::string ImagesText(const std::vector<trainer::Camera>& cameras) {
  std::string text = "# Image list with two lines of data per image:\n#   IMAGE_ID, QW, ...\n";
  char line[512];
  for (size_t i = 0; i < cameras.size(); ++i) {
    double q[4], t[3];
    ColmapPoseFromC2w(cameras[i].c2w, q, t);
    std::snprintf(line, sizeof(line),
                  "%zu %.17g %.17g %.17g %.17g %.17g %.17g %.17g 1 frame %03zu.png\n", i + 1, q[0],
                  q[1], q[2], q[3], t[0], t[1], t[2], i);
    text += line;
    text += i % 2 ? "\n" : "12.5 7.25 -1 3.0 4.0 17\n";  // the 2-D points line, empty or not
  }
  return text;
}

TEST(ColmapModel, PosesRoundTripThroughColmapsConvention) {
  const trainer::Dataset capture = trainer::MakeCaptureScene("train", 32, 24, 16, 7);
  std::vector<trainer::Camera> cameras;
  for (const trainer::View& v : capture.views) cameras.push_back(v.camera);
  const std::vector<ColmapImage> images = ParseColmapImages(ImagesText(cameras), "images.txt");
  ASSERT_EQ(images.size(), cameras.size());
  for (size_t i = 0; i < images.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame %03zu.png", i);
    EXPECT_EQ(images[i].name, name);  // spaces kept
    EXPECT_EQ(images[i].camera_id, 1);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) EXPECT_NEAR(images[i].c2w[r][c], cameras[i].c2w[r][c], 1e-12);
  }
  // A known pose: the identity world-to-camera rotation is a camera at the origin looking down
  // +z with +y down (OpenCV), i.e. down -z_gl = +z_world... with y and z flipped.
  const std::vector<ColmapImage> one =
      ParseColmapImages("1 1 0 0 0 0 0 -2 1 a.jpg\n\n", "images.txt");
  ASSERT_EQ(one.size(), 1u);
  const double expected[3][4] = {{1, 0, 0, 0}, {0, -1, 0, 0}, {0, 0, -1, 2}};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) EXPECT_EQ(one[0].c2w[r][c], expected[r][c]) << r << c;
}

TEST(ColmapModel, ReadsEveryCameraModelTheLoaderCanExpress) {
  const auto cams = ParseColmapCameras(
      "# Camera list\n"
      "1 SIMPLE_PINHOLE 640 480 500 320 240\n"
      "2 PINHOLE 640 480 500 510 321 241\n"
      "3 SIMPLE_RADIAL 640 480 500 320 240 -0.1\n"
      "4 RADIAL 640 480 500 320 240 -0.1 0.02\n"
      "5 OPENCV 800 600 700 710 401 299 -0.12 0.03 0.001 -0.002\n",
      "cameras.txt");
  ASSERT_EQ(cams.size(), 5u);
  EXPECT_EQ(cams.at(1).fy, 500);
  EXPECT_EQ(cams.at(1).cx, 320);
  EXPECT_EQ(cams.at(2).fy, 510);
  EXPECT_EQ(cams.at(2).cy, 241);
  EXPECT_EQ(cams.at(3).k1, -0.1);
  EXPECT_EQ(cams.at(4).k2, 0.02);
  const ColmapCamera& c = cams.at(5);
  EXPECT_EQ(c.width, 800);
  EXPECT_EQ(c.height, 600);
  EXPECT_EQ(c.fx, 700);
  EXPECT_EQ(c.fy, 710);
  EXPECT_EQ(c.cx, 401);
  EXPECT_EQ(c.cy, 299);
  EXPECT_EQ(c.k1, -0.12);
  EXPECT_EQ(c.k2, 0.03);
  EXPECT_EQ(c.p1, 0.001);
  EXPECT_EQ(c.p2, -0.002);
}

TEST(ColmapModel, BadLinesNameTheFileLineAndProblem) {
  auto cameras = [](const std::string& text) {
    return ErrorOf([&] { ParseColmapCameras(text, "cameras.txt"); });
  };
  EXPECT_NE(cameras("# c\n\n1 OPENCV_FISHEYE 64 48 1 1 1 1 0 0 0 0\n")
                .find("cameras.txt:3: camera model OPENCV_FISHEYE is not supported"),
            std::string::npos);
  EXPECT_NE(
      cameras("1 PINHOLE 64 48 50 50 32\n").find("PINHOLE needs 4 parameters, the line has 3"),
      std::string::npos);
  EXPECT_NE(cameras("1 PINHOLE 64 48 50 nan 32 24\n").find("is not a finite number"),
            std::string::npos);
  EXPECT_NE(cameras("1 PINHOLE 64 48 -5 5 32 24\n").find("focal length must be positive"),
            std::string::npos);
  EXPECT_NE(cameras("1 PINHOLE 64 48 5 5 32 24\n1 PINHOLE 64 48 5 5 32 24\n").find("appears twice"),
            std::string::npos);
  auto images = [](const std::string& text) {
    return ErrorOf([&] { ParseColmapImages(text, "images.txt"); });
  };
  EXPECT_NE(images("1 1 0 0 0 0 0 0 1\n").find("images.txt:1: expected IMAGE_ID"),
            std::string::npos);
  EXPECT_NE(images("1 2 0 0 0 0 0 0 1 a.png\n\n").find("not a unit quaternion"), std::string::npos);
  // An image of a camera cameras.txt does not list.
  const fs::path dir =
      fs::temp_directory_path() / ("colmap_model_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "cameras.txt") << "1 PINHOLE 64 48 50 50 32 24\n";
  std::ofstream(dir / "images.txt") << "1 1 0 0 0 0 0 0 2 a.png\n\n";
  EXPECT_NE(ErrorOf([&] { ReadColmapTextModel(dir.string()); }).find("names camera 2"),
            std::string::npos);
  fs::remove_all(dir);
}

// Cameras on a tilted ring around a point, looking at it, in an arbitrary frame: normalised,
// the point is the origin, up is +z and the mean distance is 4.
TEST(ColmapModel, NormalisedPosesLookAtTheOriginWithZUp) {
  const double centre[3] = {3.0, -1.5, 7.0};
  const double tilt = 0.6;  // the ring's up, rotated about x
  const double up[3] = {0, std::cos(tilt), std::sin(tilt)};
  const double e1[3] = {1, 0, 0};
  const double e2[3] = {0, -std::sin(tilt), std::cos(tilt)};
  std::vector<ColmapImage> images(24);
  for (size_t i = 0; i < images.size(); ++i) {
    const double a = 2 * M_PI * double(i) / double(images.size());
    const double radius = 2.5 + 0.3 * std::sin(3 * a);
    double o[3], back[3], right[3], cam_up[3];
    for (int k = 0; k < 3; ++k)
      o[k] = centre[k] + radius * (std::cos(a) * e1[k] + std::sin(a) * e2[k]) + 0.4 * up[k];
    double norm = 0;
    for (int k = 0; k < 3; ++k) norm += (o[k] - centre[k]) * (o[k] - centre[k]);
    for (int k = 0; k < 3; ++k) back[k] = (o[k] - centre[k]) / std::sqrt(norm);  // +z_gl
    right[0] = up[1] * back[2] - up[2] * back[1];
    right[1] = up[2] * back[0] - up[0] * back[2];
    right[2] = up[0] * back[1] - up[1] * back[0];
    norm = std::sqrt(right[0] * right[0] + right[1] * right[1] + right[2] * right[2]);
    for (double& v : right) v /= norm;
    cam_up[0] = back[1] * right[2] - back[2] * right[1];
    cam_up[1] = back[2] * right[0] - back[0] * right[2];
    cam_up[2] = back[0] * right[1] - back[1] * right[0];
    for (int k = 0; k < 3; ++k) {
      images[i].c2w[k][0] = right[k];
      images[i].c2w[k][1] = cam_up[k];
      images[i].c2w[k][2] = back[k];
      images[i].c2w[k][3] = o[k];
    }
  }
  NormalizeColmapPoses(&images, 4.0);
  double mean = 0, up_sum[3] = {0, 0, 0};
  for (const ColmapImage& im : images) {
    const double o[3] = {im.c2w[0][3], im.c2w[1][3], im.c2w[2][3]};
    const double d[3] = {-im.c2w[0][2], -im.c2w[1][2], -im.c2w[2][2]};
    mean += std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]) / double(images.size());
    // The optical axis passes through the origin: o x d = 0.
    const double cx = o[1] * d[2] - o[2] * d[1], cy = o[2] * d[0] - o[0] * d[2],
                 cz = o[0] * d[1] - o[1] * d[0];
    EXPECT_NEAR(std::sqrt(cx * cx + cy * cy + cz * cz), 0.0, 1e-9);
    for (int k = 0; k < 3; ++k) up_sum[k] += im.c2w[k][1];
    // Still a rotation.
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        double dot = 0;
        for (int k = 0; k < 3; ++k) dot += im.c2w[k][a] * im.c2w[k][b];
        EXPECT_NEAR(dot, a == b ? 1.0 : 0.0, 1e-12);
      }
  }
  EXPECT_NEAR(mean, 4.0, 1e-12);
  const double n = std::sqrt(up_sum[0] * up_sum[0] + up_sum[1] * up_sum[1] + up_sum[2] * up_sum[2]);
  EXPECT_NEAR(up_sum[2] / n, 1.0, 1e-12);
}

// transforms.json as the trainer's loader reads it: intrinsics, distortion and poses.
TEST(ColmapModel, TransformsJsonLoadsWithTheSameCameras) {
  const fs::path dir =
      fs::temp_directory_path() / ("colmap_json_test_" + std::to_string(::getpid()));
  fs::create_directories(dir / "images");
  ColmapModel model;
  model.cameras =
      ParseColmapCameras("1 OPENCV 32 24 30 31 16.5 11.5 -0.12 0.03 0.001 -0.002\n", "c");
  const trainer::Dataset capture = trainer::MakeCaptureScene("train", 32, 24, 10, 3);
  std::vector<trainer::Camera> cameras;
  for (const trainer::View& v : capture.views) cameras.push_back(v.camera);
  model.images = ParseColmapImages(ImagesText(cameras), "i");
  for (const ColmapImage& im : model.images)
    trainer::SavePng((dir / "images" / im.name).string(), capture.views[0].rgb);
  std::ofstream(dir / "transforms.json") << TransformsJson(model, model.images, 16, "images");
  size_t loaded = 0;
  for (const char* split : {"train", "test"}) {
    const trainer::DatasetManifest m = trainer::ReadDatasetManifest(dir.string(), split, 1);
    for (const trainer::ViewSource& v : m.views) {
      const size_t i = size_t(std::stoi(v.name.substr(v.name.size() - 3)));
      ++loaded;
      EXPECT_EQ(v.camera.fx, 30);
      EXPECT_EQ(v.camera.fy, 31);
      EXPECT_EQ(v.camera.cx, 16.5);
      EXPECT_EQ(v.camera.cy, 11.5);
      EXPECT_EQ(v.camera.k1, -0.12);
      EXPECT_EQ(v.camera.p2, -0.002);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(v.camera.c2w[r][c], cameras[i].c2w[r][c], 1e-12);
    }
  }
  EXPECT_EQ(loaded, cameras.size());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
