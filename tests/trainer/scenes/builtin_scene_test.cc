#include "trainer/scenes/builtin_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "trainer/data/camera.h"

namespace ecrf::trainer {
namespace {

TEST(BuiltinScene, IsDeterministicForASeed) {
  const Dataset a = MakeBuiltinScene("train", 32, 32, 6, 42);
  const Dataset b = MakeBuiltinScene("train", 32, 32, 6, 42);
  ASSERT_EQ(a.views.size(), 6u);
  for (size_t v = 0; v < a.views.size(); ++v) {
    EXPECT_EQ(a.views[v].rgb.pixels, b.views[v].rgb.pixels);
    EXPECT_EQ(a.views[v].name, b.views[v].name);
  }
  const Dataset other_seed = MakeBuiltinScene("train", 32, 32, 6, 43);
  EXPECT_NE(a.views[0].camera.c2w[0][3], other_seed.views[0].camera.c2w[0][3]);
}

TEST(BuiltinScene, UsesBlenderConventions) {
  const Dataset scene = MakeBuiltinScene("test", 40, 30, 3, 1);
  EXPECT_TRUE(scene.white_background);
  EXPECT_EQ(scene.near, 2.0);
  EXPECT_EQ(scene.far, 6.0);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(scene.scene_aabb[0][a], -1.5);
    EXPECT_EQ(scene.scene_aabb[1][a], 1.5);
  }
  const View& view = scene.views[0];
  EXPECT_EQ(view.rgb.width, 40);
  EXPECT_EQ(view.rgb.height, 30);
  EXPECT_EQ(view.rgb.channels, 3);
  EXPECT_EQ(view.camera.width, 40);
  EXPECT_DOUBLE_EQ(view.camera.fx, FocalFromFieldOfView(40, kBuiltinFieldOfView));
}

TEST(BuiltinScene, CamerasSitOnTheSphereAndLookAtTheOrigin) {
  for (const char* split : {"train", "test", "val"}) {
    const Dataset scene = MakeBuiltinScene(split, 16, 16, 20, 7);
    for (const View& view : scene.views) {
      float origin[3], dir[3];
      GenerateRay(view.camera, 7.5, 7.5, origin, dir);  // exact image centre
      EXPECT_NEAR(std::sqrt(origin[0] * origin[0] + origin[1] * origin[1] + origin[2] * origin[2]),
                  kBuiltinCameraDistance, 1e-5);
      EXPECT_GT(origin[2], 0) << "upper hemisphere";
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(dir[a], -origin[a] / kBuiltinCameraDistance, 1e-5);
    }
  }
}

TEST(BuiltinScene, TrainAndTestViewsDiffer) {
  const Dataset train = MakeBuiltinScene("train", 24, 24, 8, 3);
  const Dataset test = MakeBuiltinScene("test", 24, 24, 8, 3);
  for (const View& t : test.views) {
    for (const View& r : train.views) {
      double distance = 0;
      for (int a = 0; a < 3; ++a) distance += std::pow(t.camera.c2w[a][3] - r.camera.c2w[a][3], 2);
      EXPECT_GT(std::sqrt(distance), 1e-3);
    }
  }
  EXPECT_NE(train.views[0].rgb.pixels, test.views[0].rgb.pixels);
  EXPECT_NE(train.views[0].name, test.views[0].name);
}

TEST(BuiltinScene, ShowsObjectsWithVarietyOnWhite) {
  const Dataset scene = MakeBuiltinScene("test", 64, 64, 4, 0);
  for (const View& view : scene.views) {
    int white = 0, object = 0, reddish = 0, bluish = 0, greenish = 0;
    for (int y = 0; y < 64; ++y) {
      for (int x = 0; x < 64; ++x) {
        const float r = view.rgb.at(x, y, 0), g = view.rgb.at(x, y, 1), b = view.rgb.at(x, y, 2);
        ASSERT_TRUE(r >= 0 && r <= 1 && g >= 0 && g <= 1 && b >= 0 && b <= 1);
        if (r == 1 && g == 1 && b == 1) ++white;
        if (r < 0.9f || g < 0.9f || b < 0.9f) ++object;
        if (r > g + 0.3f && r > b + 0.3f) ++reddish;
        if (b > r + 0.2f && b > g + 0.1f) ++bluish;
        if (g > r + 0.15f && g > b + 0.15f) ++greenish;
      }
    }
    EXPECT_GT(white, 64 * 64 / 10) << view.name;
    EXPECT_GT(object, 64 * 64 / 5) << view.name;
    EXPECT_GT(reddish, 10) << view.name;
    EXPECT_GT(bluish + greenish, 10) << view.name;
  }
}

TEST(BuiltinScene, RejectsBadArguments) {
  EXPECT_THROW(MakeBuiltinScene("holdout", 8, 8, 1, 0), std::runtime_error);
  EXPECT_THROW(MakeBuiltinScene("train", 0, 8, 1, 0), std::runtime_error);
  EXPECT_THROW(MakeBuiltinScene("train", 8, 8, 0, 0), std::runtime_error);
}

}  // namespace
}  // namespace ecrf::trainer
