// render's camera paths: the orbit and the spiral have the documented poses (the formula in
// tools/camera_path.h and `ecrf render --help`) and look at the origin, and a path written as
// JSON (--save-path) reads back (--path) to the same cameras, bit for bit.
#include "tools/camera_path.h"
#include "tests/common/scoped_temp_dir.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "decoder/camera.h"
#include "tools/camera_path_json.h"

namespace ecrf {
namespace tools {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Spherical {
  double azimuth_deg, elevation_deg, radius;
};

// Where a camera sits, in the orbit's spherical coordinates.
Spherical PositionOf(const trainer::Camera& c) {
  const double x = c.c2w[0][3], y = c.c2w[1][3], z = c.c2w[2][3];
  const double r = std::sqrt(x * x + y * y + z * z);
  double azimuth = std::atan2(y, x) * 180.0 / kPi;
  if (azimuth < -1e-3) azimuth += 360.0;
  return {azimuth, std::asin(z / r) * 180.0 / kPi, r};
}

// The camera looks at the origin (its -z axis points from its centre to the origin), its
// rotation is orthonormal and it is upright (+y has no component against world +z).
void ExpectLooksAtOrigin(const trainer::Camera& c) {
  const double x = c.c2w[0][3], y = c.c2w[1][3], z = c.c2w[2][3];
  const double r = std::sqrt(x * x + y * y + z * z);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(c.c2w[a][2], c.c2w[a][3] / r, 1e-6) << "axis " << a;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double dot = 0;
      for (int a = 0; a < 3; ++a) dot += c.c2w[a][i] * c.c2w[a][j];
      EXPECT_NEAR(dot, i == j ? 1.0 : 0.0, 1e-6) << i << "," << j;
    }
  }
  EXPECT_GT(c.c2w[2][1], 0.0);          // camera +y has world +z in it
  EXPECT_NEAR(c.c2w[2][0], 0.0, 1e-6);  // camera +x stays horizontal: no roll
}

void ExpectSameCamera(const trainer::Camera& a, const trainer::Camera& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.fx, b.fx);
  EXPECT_EQ(a.fy, b.fy);
  EXPECT_EQ(a.cx, b.cx);
  EXPECT_EQ(a.cy, b.cy);
  EXPECT_EQ(a.k1, b.k1);
  EXPECT_EQ(a.k2, b.k2);
  EXPECT_EQ(a.p1, b.p1);
  EXPECT_EQ(a.p2, b.p2);
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 4; ++k) EXPECT_EQ(a.c2w[r][k], b.c2w[r][k]) << r << "," << k;
  }
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::string ErrorOf(const std::string& file, int width = 64, int height = 48) {
  try {
    ReadCameraPath(file, width, height);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(CameraPath, FrameNamesFollowTheFfmpegPattern) {
  EXPECT_EQ(FrameName("orbit", 7), "orbit_007");
  EXPECT_EQ(FrameName("spiral", 123), "spiral_123");
  EXPECT_EQ(FrameName("path", 1234), "path_1234");
  for (int k : {0, 9, 999, 1000, 123456}) {
    char printed[64];
    std::snprintf(printed, sizeof(printed), FramePattern("orbit").c_str(), k);
    EXPECT_EQ(printed, FrameName("orbit", k));
  }
}

TEST(CameraPath, OrbitIsTheDecodersOrbitCamera) {
  OrbitShape shape;
  shape.width = 40;
  shape.height = 30;
  shape.radius = 3.5;
  shape.elevation_deg = 25.0;
  const std::vector<PathCamera> path = OrbitPath(12, shape);
  ASSERT_EQ(path.size(), 12u);
  EXPECT_EQ(path.front().name, "orbit_000");
  EXPECT_EQ(path.back().name, "orbit_011");
  for (int k = 0; k < 12; ++k) {
    SCOPED_TRACE(k);
    const trainer::Camera& c = path[k].camera;
    // Frame k is OrbitCameraDegrees(W, H, 360.0 * k / N, ...), as `ecrf render --orbit` always
    // rendered it (decoder/camera.h).
    const dec::Camera d = dec::OrbitCameraDegrees(40, 30, 360.0 * k / 12, 25.0, 3.5f);
    for (int r = 0; r < 3; ++r) {
      for (int j = 0; j < 4; ++j) EXPECT_EQ(c.c2w[r][j], d.c2w[4 * r + j]);
    }
    EXPECT_EQ(c.fx, d.fx);
    EXPECT_EQ(c.width, 40);
    EXPECT_EQ(c.height, 30);
    EXPECT_EQ(c.cx, 20.0);
    EXPECT_EQ(c.cy, 15.0);
    const Spherical p = PositionOf(c);
    EXPECT_NEAR(p.azimuth_deg, 30.0 * k, 1e-4);
    EXPECT_NEAR(p.elevation_deg, 25.0, 1e-4);
    EXPECT_NEAR(p.radius, 3.5, 1e-5);
    ExpectLooksAtOrigin(c);
  }
  // The first camera sits on the +x side of the origin, 25 degrees up.
  const double e = 25.0 * kPi / 180.0;
  EXPECT_NEAR(path[0].camera.c2w[0][3], 3.5 * std::cos(e), 1e-5);
  EXPECT_NEAR(path[0].camera.c2w[1][3], 0.0, 1e-6);
  EXPECT_NEAR(path[0].camera.c2w[2][3], 3.5 * std::sin(e), 1e-5);
}

TEST(CameraPath, SpiralFollowsTheDocumentedFormula) {
  OrbitShape shape;  // 400x400, radius 4, elevation 30: the defaults
  SpiralShape spiral;
  spiral.elevation_amplitude_deg = 20.0;
  spiral.radius_amplitude = 0.25;
  spiral.cycles = 2;
  const int n = 16;
  const std::vector<PathCamera> path = SpiralPath(n, shape, spiral);
  ASSERT_EQ(path.size(), size_t(n));
  EXPECT_EQ(path[3].name, "spiral_003");
  double lowest = 90, highest = -90, nearest = 1e9, farthest = 0;
  for (int k = 0; k < n; ++k) {
    SCOPED_TRACE(k);
    const Spherical p = PositionOf(path[k].camera);
    const double s = std::sin(2.0 * kPi * 2 * k / n);
    EXPECT_NEAR(p.azimuth_deg, 360.0 * k / n, 1e-4);
    EXPECT_NEAR(p.elevation_deg, 30.0 + 20.0 * s, 1e-4);
    EXPECT_NEAR(p.radius, 4.0 * (1.0 + 0.25 * s), 1e-5);
    ExpectLooksAtOrigin(path[k].camera);
    lowest = std::min(lowest, p.elevation_deg);
    highest = std::max(highest, p.elevation_deg);
    nearest = std::min(nearest, p.radius);
    farthest = std::max(farthest, p.radius);
  }
  // p = sin(pi k / 4) reaches +1 at k = 2 and -1 at k = 6: the swing's bounds are reached, not
  // passed.
  EXPECT_NEAR(highest, 50.0, 1e-4);
  EXPECT_NEAR(lowest, 10.0, 1e-4);
  EXPECT_NEAR(farthest, 5.0, 1e-5);
  EXPECT_NEAR(nearest, 3.0, 1e-5);
  // Frame 0 is the orbit's frame 0, bit for bit.
  const std::vector<PathCamera> orbit = OrbitPath(n, shape);
  ExpectSameCamera(path[0].camera, orbit[0].camera);
  // Frame N (one past the end) is frame 0 again: the video loops.
  const OrbitPose end = SpiralPoseAt(n, n, shape, spiral),
                  start = SpiralPoseAt(0, n, shape, spiral);
  EXPECT_NEAR(end.elevation_deg, start.elevation_deg, 1e-9);
  EXPECT_NEAR(end.radius, start.radius, 1e-9);
  EXPECT_NEAR(end.azimuth_deg, start.azimuth_deg + 360.0, 1e-9);
}

TEST(CameraPath, SpiralStaysClearOfThePoles) {
  OrbitShape shape;
  SpiralShape spiral;
  EXPECT_EQ(SpiralProblem(shape, spiral), "");  // the defaults: 30 +- 15 degrees
  shape.elevation_deg = -70.0;
  spiral.elevation_amplitude_deg = 20.0;
  const std::string pole = SpiralProblem(shape, spiral);
  EXPECT_NE(pole.find("--elevation -70 with --spiral-elevation 20 reaches 90"), std::string::npos)
      << pole;
  spiral.elevation_amplitude_deg = 19.0;
  EXPECT_EQ(SpiralProblem(shape, spiral), "");
  spiral.radius_amplitude = 1.0;
  EXPECT_NE(SpiralProblem(shape, spiral).find("--spiral-radius"), std::string::npos);
}

TEST(CameraPathJson, SavedPathReadsBackBitForBit) {
  const testing_util::ScopedTempDir tmp("ecrf_camera_path_test");
  const std::string dir = tmp.path();
  OrbitShape shape;
  shape.width = 64;
  shape.height = 48;
  const std::vector<PathCamera> spiral = SpiralPath(7, shape, SpiralShape());
  WriteCameraPath(dir + "/spiral.json", spiral);
  // The transforms.json convention: shared intrinsics at the top, one transform_matrix a frame.
  std::ifstream in(dir + "/spiral.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["w"], 64);
  EXPECT_EQ(j["h"], 48);
  EXPECT_TRUE(j.contains("fl_x"));
  ASSERT_EQ(j["frames"].size(), 7u);
  EXPECT_EQ(j["frames"][2]["file_path"], "spiral_002");
  EXPECT_EQ(j["frames"][2]["transform_matrix"][3], nlohmann::json::parse("[0.0, 0.0, 0.0, 1.0]"));
  // -W / -H are only defaults: the file's w and h win.
  const std::vector<PathCamera> back = ReadCameraPath(dir + "/spiral.json", 999, 999);
  ASSERT_EQ(back.size(), spiral.size());
  for (size_t k = 0; k < back.size(); ++k) {
    SCOPED_TRACE(k);
    EXPECT_EQ(back[k].name, FrameName("path", int(k)));
    ExpectSameCamera(back[k].camera, spiral[k].camera);
  }
}

TEST(CameraPathJson, CamerasOfDifferentSizesKeepTheirIntrinsicsPerFrame) {
  const testing_util::ScopedTempDir tmp("ecrf_camera_path_test");
  const std::string dir = tmp.path();
  std::vector<PathCamera> path = OrbitPath(2, OrbitShape());
  path[1].camera = OrbitView(32, 16, {45.0, 10.0, 2.5});
  path[1].camera.k1 = 0.01;  // distortion travels too
  path[1].camera.p2 = -0.002;
  WriteCameraPath(dir + "/mixed.json", path);
  std::ifstream in(dir + "/mixed.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_FALSE(j.contains("w"));
  EXPECT_EQ(j["frames"][1]["w"], 32);
  const std::vector<PathCamera> back = ReadCameraPath(dir + "/mixed.json", 400, 400);
  ASSERT_EQ(back.size(), 2u);
  ExpectSameCamera(back[0].camera, path[0].camera);
  ExpectSameCamera(back[1].camera, path[1].camera);
}

TEST(CameraPathJson, AHandWrittenPathNeedsNoImagesNorSizes) {
  const testing_util::ScopedTempDir tmp("ecrf_camera_path_test");
  const std::string dir = tmp.path();
  WriteText(dir + "/path.json", R"({
    "camera_angle_x": 0.6911112070083618,
    "frames": [
      {"transform_matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 4], [0, 0, 0, 1]]},
      {"transform_matrix": [[0, 0, 1, 4], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1]]}
    ]})");
  const std::vector<PathCamera> path = ReadCameraPath(dir + "/path.json", 64, 48);
  ASSERT_EQ(path.size(), 2u);
  EXPECT_EQ(path[1].name, "path_001");
  const trainer::Camera& c = path[0].camera;
  EXPECT_EQ(c.width, 64);
  EXPECT_EQ(c.height, 48);
  EXPECT_NEAR(c.fx, 32.0 / std::tan(0.5 * 0.6911112070083618), 1e-9);
  EXPECT_EQ(c.fy, c.fx);
  EXPECT_EQ(c.cx, 32.0);
  EXPECT_EQ(c.cy, 24.0);
  EXPECT_EQ(c.c2w[2][3], 4.0);
  EXPECT_EQ(path[1].camera.c2w[0][3], 4.0);
}

TEST(CameraPathJson, ErrorsNameTheFileTheFrameAndTheProblem) {
  const testing_util::ScopedTempDir tmp("ecrf_camera_path_test");
  const std::string dir = tmp.path();
  const std::string file = dir + "/bad.json";
  WriteText(file, R"({"camera_angle_x": 0.7, "frames": [{"transform_matrix": [[1, 0, 0, 0],
    [0, 1, 0, 0], [0, 0, 1, 4], [0, 0, 0, 1]]}, {"transform_matrix": [[2, 0, 0, 0],
    [0, 1, 0, 0], [0, 0, 1, 4], [0, 0, 0, 1]]}]})");
  std::string e = ErrorOf(file);
  EXPECT_EQ(e.rfind(file + ": frame 1", 0), 0u) << e;  // the user's file, not the private copy
  EXPECT_NE(e.find("transform_matrix"), std::string::npos) << e;
  EXPECT_EQ(e.find("ecrf_path_"), std::string::npos) << e;
  WriteText(file, R"({"frames": [{"transform_matrix": [[1, 0, 0, 0], [0, 1, 0, 0],
    [0, 0, 1, 4], [0, 0, 0, 1]]}]})");
  e = ErrorOf(file);
  EXPECT_EQ(e.rfind(file + ": frame 0", 0), 0u) << e;
  EXPECT_NE(e.find("no focal length: need 'fl_x' or 'camera_angle_x'"), std::string::npos) << e;
  WriteText(file, R"({"camera_angle_x": 0.7, "frames": []})");
  EXPECT_EQ(ErrorOf(file), file + ": 'frames' is empty");
  WriteText(file, "[1, 2");
  e = ErrorOf(file);
  EXPECT_EQ(e.rfind(file + ": invalid JSON", 0), 0u) << e;
  e = ErrorOf(dir + "/missing.json");
  EXPECT_EQ(e.rfind(dir + "/missing.json: cannot open", 0), 0u) << e;
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
