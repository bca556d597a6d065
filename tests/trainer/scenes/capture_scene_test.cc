#include "trainer/scenes/capture_scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>

#include "tests/common/held_out_frames.h"
#include "tests/common/worn_shade.h"
#include "trainer/data/camera.h"
#include "trainer/data/ray_set.h"
#include "trainer/scenes/capture_room.h"
#include "trainer/scenes/still_life.h"

namespace ecrf::trainer {
namespace {

TEST(CaptureScene, IsDeterministicForASeed) {
  const Dataset a = MakeCaptureScene("train", 40, 30, 12, 42);
  const Dataset b = MakeCaptureScene("train", 40, 30, 12, 42);
  ASSERT_EQ(a.views.size(), b.views.size());
  for (size_t v = 0; v < a.views.size(); ++v) {
    EXPECT_EQ(a.views[v].rgb.pixels, b.views[v].rgb.pixels);
    EXPECT_EQ(a.views[v].name, b.views[v].name);
  }
  const Dataset other_seed = MakeCaptureScene("train", 40, 30, 12, 43);
  EXPECT_NE(a.views[0].camera.c2w[0][3], other_seed.views[0].camera.c2w[0][3]);
  EXPECT_NE(a.views[0].rgb.pixels, other_seed.views[0].rgb.pixels);
}

TEST(CaptureScene, CamerasHaveTheOffCentreDistortingLens) {
  const Dataset scene = MakeCaptureScene("test", 120, 90, 16, 1);
  for (const View& view : scene.views) {
    const Camera& c = view.camera;
    EXPECT_EQ(c.width, 120);
    EXPECT_EQ(c.height, 90);
    EXPECT_DOUBLE_EQ(c.fx, FocalFromFieldOfView(120, kCaptureFieldOfView));
    EXPECT_DOUBLE_EQ(c.fy, c.fx);
    EXPECT_DOUBLE_EQ(c.cx, 120 * (0.5 + kCaptureCxOffset));
    EXPECT_DOUBLE_EQ(c.cy, 90 * (0.5 + kCaptureCyOffset));
    EXPECT_NE(c.cx, 60.0);
    EXPECT_NE(c.cy, 45.0);
    EXPECT_EQ(c.k1, kCaptureK1);
    EXPECT_EQ(c.k2, kCaptureK2);
    EXPECT_EQ(c.p1, 0.0);
    EXPECT_EQ(c.p2, 0.0);
    EXPECT_TRUE(c.HasDistortion());
    EXPECT_EQ(view.rgb.width, 120);
    EXPECT_EQ(view.rgb.height, 90);
    EXPECT_EQ(view.rgb.channels, 3);
  }
}

// The images are what the training rays see: a pixel's colour is the radiance along the ray
// RaySet makes for it (undistorted through the principal point), bit for bit.
TEST(CaptureScene, PixelsAreTheRadianceAlongTheirDatasetRays) {
  const Dataset scene = MakeCaptureScene("train", 48, 36, 9, 5);
  RaySet rays(scene.views);
  ASSERT_EQ(rays.total(), scene.views.size() * 48 * 36);
  for (uint32_t index = 0; index < rays.total(); index += 7) {
    float origin[3], dir[3], rgb[3], direct[3];
    rays.Ray(index, origin, dir, rgb);
    CaptureSceneRadiance(origin, dir, direct);
    for (int c = 0; c < 3; ++c) ASSERT_EQ(rgb[c], direct[c]) << "ray " << index;
  }
  // The distortion matters: the undistorted pinhole ray through a corner pixel sees elsewhere.
  const Camera& camera = scene.views[0].camera;
  Camera pinhole = camera;
  pinhole.k1 = pinhole.k2 = 0;
  float o[3], distorted[3], straight[3];
  GenerateRay(camera, 0, 0, o, distorted);
  GenerateRay(pinhole, 0, 0, o, straight);
  double gap = 0;
  for (int a = 0; a < 3; ++a) gap += std::abs(distorted[a] - straight[a]);
  EXPECT_GT(gap, 1e-2);
}

TEST(CaptureScene, EveryEighthFrameIsATestView) {
  const int frames = 50;
  const Dataset train = MakeCaptureScene("train", 16, 12, frames, 3);
  const Dataset test = MakeCaptureScene("test", 16, 12, frames, 3);
  const Dataset val = MakeCaptureScene("val", 16, 12, frames, 3);
  ExpectEveryEighthFrameHeldOut(train, test, val, frames, "capture");
  // Neighbouring frames of the loop are close: test frame 8 sits between train frames 7 and 9.
  auto distance = [](const Camera& a, const Camera& b) {
    return std::hypot(a.c2w[0][3] - b.c2w[0][3], a.c2w[1][3] - b.c2w[1][3],
                      a.c2w[2][3] - b.c2w[2][3]);
  };
  EXPECT_LT(distance(test.views[1].camera, train.views[6].camera), 0.5);  // frame 8 vs frame 7
  EXPECT_LT(distance(test.views[1].camera, train.views[7].camera), 0.5);  // frame 8 vs frame 9
}

bool MissesBoundingSphere(const float origin[3], const float dir[3]) {
  const double b = origin[0] * dir[0] + origin[1] * dir[1] + origin[2] * dir[2];
  const double c = origin[0] * origin[0] + origin[1] * origin[1] + origin[2] * origin[2] -
                   procedural::kStillLifeRadius * procedural::kStillLifeRadius;
  return b * b - c < 0;
}

// Where the builtin scene shows its white background the capture shows the textured room:
// every pixel is the still life or a room surface, and the room is a good part of each view.
TEST(CaptureScene, TheRoomFillsEveryViewAndTheObjectIsInIt) {
  const Dataset scene = MakeCaptureScene("train", 60, 45, 24, 9);
  EXPECT_FALSE(scene.white_background);
  for (const View& view : scene.views) {
    int room = 0, centre_object = 0;
    std::set<int> room_colours;
    double least_wear = 1, most_wear = 0;
    for (int y = 0; y < 45; ++y) {
      for (int x = 0; x < 60; ++x) {
        float origin[3], dir[3];
        GenerateRay(view.camera, x, y, origin, dir);
        const procedural::Vec3 o{origin[0], origin[1], origin[2]};
        const procedural::Vec3 d = procedural::Normalized({dir[0], dir[1], dir[2]});
        procedural::Vec3 colour;
        if (procedural::ShadeStillLife(o, d, &colour)) continue;
        colour = procedural::ShadeRoom(kCaptureRoomMin, kCaptureRoomMax, o, d);
        const float r = view.rgb.at(x, y, 0), g = view.rgb.at(x, y, 1), b = view.rgb.at(x, y, 2);
        ASSERT_TRUE(IsWornShade(r, g, b, colour)) << view.name << " at " << x << "," << y;
        const double wear = WearOf(r, g, b, colour);
        least_wear = std::min(least_wear, wear);
        most_wear = std::max(most_wear, wear);
        ASSERT_FALSE(r == 1 && g == 1 && b == 1)
            << view.name << " shows background at " << x << "," << y;
        ++room;
        room_colours.insert(int(r * 15) * 256 + int(g * 15) * 16 + int(b * 15));
      }
    }
    EXPECT_GT(room, 60 * 45 / 5) << view.name << ": the room is not the background";
    EXPECT_GE(room_colours.size(), 8u) << view.name << ": the room is not textured";
    // Worn unevenly, so that no two tiles of a pattern look alike (photos of periodic surfaces
    // match wrongly: docs/photos-to-dataset.md).
    EXPECT_LT(least_wear, 0.9) << view.name;
    EXPECT_GT(most_wear, 0.97) << view.name;
    // The middle of the frame looks at the still life.
    for (int y = 18; y < 27; ++y) {
      for (int x = 24; x < 36; ++x) {
        float origin[3], dir[3];
        GenerateRay(view.camera, x, y, origin, dir);
        centre_object += !MissesBoundingSphere(origin, dir);
      }
    }
    EXPECT_EQ(centre_object, 9 * 12) << view.name << " does not look at the object";
    // Cameras move about inside the room, at hand height.
    for (int a = 0; a < 3; ++a) {
      EXPECT_GT(view.camera.c2w[a][3], kCaptureRoomMin[a] + 0.3);
      EXPECT_LT(view.camera.c2w[a][3], kCaptureRoomMax[a] - 0.3);
    }
  }
}

TEST(CaptureScene, AabbIsTheNgpCubeAroundTheRoom) {
  const Dataset scene = MakeCaptureScene("test", 16, 12, 8, 0);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(scene.scene_aabb[0][a], -0.5 * kCaptureAabbScale / 0.33, 1e-12);
    EXPECT_NEAR(scene.scene_aabb[1][a], 0.5 * kCaptureAabbScale / 0.33, 1e-12);
    EXPECT_LT(scene.scene_aabb[0][a], kCaptureRoomMin[a]);
    EXPECT_GT(scene.scene_aabb[1][a], kCaptureRoomMax[a]);
  }
  // Cameras inside the box: near is the floor NearFarFromCameras keeps off the lens.
  EXPECT_NEAR(scene.near, 0.01 * std::sqrt(3.0) * kCaptureAabbScale / 0.33, 1e-12);
  EXPECT_GT(scene.far, 0.5 * kCaptureAabbScale / 0.33);  // and see across it
}

TEST(CaptureScene, IsFastAndRejectsBadArguments) {
  const auto start = std::chrono::steady_clock::now();
  const Dataset train = MakeCaptureScene("train", 120, 90, 50, 0);
  const Dataset test = MakeCaptureScene("test", 120, 90, 50, 0);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(train.views.size() + test.views.size(), 50u);
  EXPECT_LT(seconds, 2.0);
  EXPECT_THROW(MakeCaptureScene("dev", 16, 12, 8, 0), std::runtime_error);
  EXPECT_THROW(MakeCaptureScene("train", 0, 12, 8, 0), std::runtime_error);
  EXPECT_THROW(MakeCaptureScene("train", 16, 12, 1, 0), std::runtime_error);
}

}  // namespace
}  // namespace ecrf::trainer
