// Rays of a camera (trainer/data/camera.h): pixel centres, the field of view, unit directions,
// lens distortion and its inverse, downscaled intrinsics, and chair's real test cameras.
#include "trainer/data/camera.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "trainer/data/dataset.h"

namespace ecrf::trainer {
namespace {

namespace fs = std::filesystem;

constexpr double kAngleX = 0.6911112070083618;  // chair's camera_angle_x

Camera BlenderCamera(int width, int height) {
  Camera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = camera.fy = FocalFromFieldOfView(width, kAngleX);
  camera.cx = width / 2.0;
  camera.cy = height / 2.0;
  return camera;
}

double AngleBetween(const float a[3], const double b[3]) {
  double dot = 0, nb = 0;
  for (int i = 0; i < 3; ++i) {
    dot += a[i] * b[i];
    nb += b[i] * b[i];
  }
  return std::acos(std::clamp(dot / std::sqrt(nb), -1.0, 1.0));
}

TEST(GenerateRay, CentrePixelLooksDownRotatedMinusZ) {
  Camera camera = BlenderCamera(4, 4);
  // Rotation by 90 degrees about +y: camera -z becomes world -x.
  const double c2w[3][4] = {{0, 0, 1, 5}, {0, 1, 0, 6}, {-1, 0, 0, 7}};
  std::copy(&c2w[0][0], &c2w[0][0] + 12, &camera.c2w[0][0]);
  float origin[3], dir[3];
  GenerateRay(camera, 1.5, 1.5, origin, dir);  // pixel-centre coordinate 2.0 = cx
  EXPECT_FLOAT_EQ(origin[0], 5);
  EXPECT_FLOAT_EQ(origin[1], 6);
  EXPECT_FLOAT_EQ(origin[2], 7);
  EXPECT_NEAR(dir[0], -1, 1e-7);
  EXPECT_NEAR(dir[1], 0, 1e-7);
  EXPECT_NEAR(dir[2], 0, 1e-7);
}

TEST(GenerateRay, ImageEdgesSpanCameraAngleX) {
  const Camera camera = BlenderCamera(400, 300);
  const double forward[3] = {0, 0, -1};
  float origin[3], left[3], right[3], top[3];
  // px = -0.5 is the left edge of pixel 0 (px + 0.5 = 0); px = 399.5 the right edge.
  GenerateRay(camera, -0.5, 149.5, origin, left);
  GenerateRay(camera, 399.5, 149.5, origin, right);
  EXPECT_NEAR(AngleBetween(left, forward), kAngleX / 2, 1e-6);
  EXPECT_NEAR(AngleBetween(right, forward), kAngleX / 2, 1e-6);
  EXPECT_LT(left[0], 0);
  EXPECT_GT(right[0], 0);
  GenerateRay(camera, 199.5, -0.5, origin, top);
  EXPECT_GT(top[1], 0);  // row 0 is the top of the image: +y in OpenGL camera space
  EXPECT_NEAR(std::atan2(top[1], -top[2]), std::atan(150.0 / camera.fy), 1e-6);
  // Pixel (0, 0) itself is sampled at its centre, half a pixel inside the corner.
  float corner[3];
  GenerateRay(camera, 0, 0, origin, corner);
  EXPECT_NEAR(corner[0] / -corner[2], (0.5 - 200) / camera.fx, 1e-6);
  EXPECT_NEAR(corner[1] / -corner[2], (150 - 0.5) / camera.fy, 1e-6);
}

TEST(GenerateRay, DirectionsAreUnitLength) {
  Camera camera = BlenderCamera(64, 48);
  camera.k1 = -0.2;
  for (int j = 0; j < 48; j += 7) {
    for (int i = 0; i < 64; i += 9) {
      float origin[3], dir[3];
      GenerateRay(camera, i, j, origin, dir);
      EXPECT_NEAR(std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]), 1.0, 1e-6);
    }
  }
}

TEST(Distortion, UndistortInvertsDistortToNanometres) {
  Camera camera = BlenderCamera(64, 64);
  camera.k1 = -0.25;
  camera.k2 = 0.06;
  camera.p1 = 0.0015;
  camera.p2 = -0.002;
  for (double y = -0.6; y <= 0.6; y += 0.1) {
    for (double x = -0.6; x <= 0.6; x += 0.1) {
      double xd, yd, xu, yu;
      DistortNormalized(camera, x, y, &xd, &yd);
      UndistortNormalized(camera, xd, yd, &xu, &yu);
      EXPECT_NEAR(xu, x, 1e-9);
      EXPECT_NEAR(yu, y, 1e-9);
    }
  }
}

TEST(Distortion, RayThroughDistortedPixelFollowsUndistortedDirection) {
  Camera camera = BlenderCamera(64, 64);
  camera.k1 = -0.2;
  camera.p2 = 0.003;
  const double x = 0.3, y = -0.2;  // OpenCV normalised, y down
  double xd, yd;
  DistortNormalized(camera, x, y, &xd, &yd);
  EXPECT_GT(std::abs(xd - x), 1e-3);  // the lens does move the point
  float origin[3], dir[3];
  GenerateRay(camera, xd * camera.fx + camera.cx - 0.5, yd * camera.fy + camera.cy - 0.5, origin,
              dir);
  EXPECT_NEAR(dir[0] / -dir[2], x, 1e-6);
  EXPECT_NEAR(dir[1] / -dir[2], -y, 1e-6);
}

TEST(ScaledCamera, DividesIntrinsicsAndKeepsPose) {
  Camera camera = BlenderCamera(401, 300);
  camera.k1 = 0.1;
  camera.c2w[0][3] = 2;
  const Camera half = ScaledCamera(camera, 2);
  EXPECT_EQ(half.width, 200);
  EXPECT_EQ(half.height, 150);
  EXPECT_DOUBLE_EQ(half.fx, camera.fx / 2);
  EXPECT_DOUBLE_EQ(half.cx, camera.cx / 2);
  EXPECT_EQ(half.k1, 0.1);
  EXPECT_EQ(half.c2w[0][3], 2);
  EXPECT_THROW(ScaledCamera(camera, 0), std::runtime_error);
}

// Runs only where the real scenes are checked out next to the project (not in CI).
TEST(RealData, ChairTestRaysThroughImageCentrePassNearOrigin) {
  const std::string dir = std::string(ECRF_SOURCE_DIR) + "/../shared/data/nerf_synthetic_400/chair";
  if (!fs::exists(dir + "/transforms_test.json")) GTEST_SKIP() << "no " << dir;
  const DatasetManifest manifest = ReadDatasetManifest(dir, "test");
  ASSERT_EQ(manifest.views.size(), 200u);
  for (const ViewSource& view : manifest.views) {
    ASSERT_EQ(view.camera.width, 400);
    float origin[3], dir3[3];
    GenerateRay(view.camera, 199.5, 199.5, origin, dir3);
    // Distance from the origin to the ray's line.
    double t = -(origin[0] * dir3[0] + origin[1] * dir3[1] + origin[2] * dir3[2]);
    double miss = 0;
    for (int a = 0; a < 3; ++a) miss += std::pow(origin[a] + t * dir3[a], 2);
    EXPECT_LT(std::sqrt(miss), 0.05) << view.name;
  }
}

}  // namespace
}  // namespace ecrf::trainer
