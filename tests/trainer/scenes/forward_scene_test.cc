#include "trainer/scenes/forward_scene.h"

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
#include "trainer/data/scene_fit.h"
#include "trainer/scenes/capture_room.h"
#include "trainer/scenes/capture_scene.h"
#include "trainer/scenes/still_life.h"
#include "trainer/train/train_options.h"
#include "trainer/train/trainer.h"

namespace ecrf::trainer {
namespace {

using procedural::Vec3;

// Every frame of a capture, in frame order: the test views are frames 0, 8, ...
std::vector<Camera> AllCameras(int width, int height, int frames, uint32_t seed) {
  const Dataset train = MakeForwardScene("train", width, height, frames, seed);
  const Dataset test = MakeForwardScene("test", width, height, frames, seed);
  std::vector<Camera> cameras;
  size_t t = 0, s = 0;
  for (int i = 0; i < frames; ++i) {
    cameras.push_back(i % 8 == 0 ? test.views.at(s++).camera : train.views.at(t++).camera);
  }
  return cameras;
}

Vec3 Centre(const Camera& c) { return {c.c2w[0][3], c.c2w[1][3], c.c2w[2][3]}; }
Vec3 ViewingAxis(const Camera& c) { return {-c.c2w[0][2], -c.c2w[1][2], -c.c2w[2][2]}; }

// The pixel's ray as the scene sees it: GenerateRay's floats, the direction renormalised.
void PixelRay(const Camera& camera, int x, int y, float origin[3], float dir[3], Vec3* o, Vec3* d) {
  GenerateRay(camera, x, y, origin, dir);
  *o = {origin[0], origin[1], origin[2]};
  *d = procedural::Normalized({dir[0], dir[1], dir[2]});
}

bool EndsOnTheFarWall(Vec3 o, Vec3 d) {
  const Vec3 end = o + d * procedural::RoomExitDistance(kCaptureRoomMin, kCaptureRoomMax, o, d);
  return std::abs(end.y - kCaptureRoomMax[1]) < 1e-9;
}

TEST(ForwardScene, IsDeterministicForASeed) {
  const Dataset a = MakeForwardScene("train", 40, 30, 12, 42);
  const Dataset b = MakeForwardScene("train", 40, 30, 12, 42);
  ASSERT_EQ(a.views.size(), b.views.size());
  for (size_t v = 0; v < a.views.size(); ++v) {
    EXPECT_EQ(a.views[v].rgb.pixels, b.views[v].rgb.pixels);
    EXPECT_EQ(a.views[v].name, b.views[v].name);
  }
  EXPECT_EQ(a.near, b.near);
  EXPECT_EQ(a.far, b.far);
  const Dataset other_seed = MakeForwardScene("train", 40, 30, 12, 43);
  EXPECT_NE(a.views[0].camera.c2w[0][3], other_seed.views[0].camera.c2w[0][3]);
  EXPECT_NE(a.views[0].rgb.pixels, other_seed.views[0].rgb.pixels);
}

TEST(ForwardScene, EveryEighthFrameIsATestView) {
  const int frames = 50;
  const Dataset train = MakeForwardScene("train", 16, 12, frames, 3);
  const Dataset test = MakeForwardScene("test", 16, 12, frames, 3);
  const Dataset val = MakeForwardScene("val", 16, 12, frames, 3);
  ExpectEveryEighthFrameHeldOut(train, test, val, frames, "forward");
  // Both splits carry the bounds of the whole capture.
  EXPECT_EQ(train.near, test.near);
  EXPECT_EQ(train.far, test.far);
  // The sweep moves a hand's width between frames: test frame 8 sits between train frames 7 and 9.
  auto distance = [](const Camera& a, const Camera& b) {
    return std::hypot(a.c2w[0][3] - b.c2w[0][3], a.c2w[1][3] - b.c2w[1][3],
                      a.c2w[2][3] - b.c2w[2][3]);
  };
  EXPECT_LT(distance(test.views[1].camera, train.views[6].camera), 0.15);  // frame 8 vs frame 7
  EXPECT_LT(distance(test.views[1].camera, train.views[7].camera), 0.15);  // frame 8 vs frame 9
}

// The LLFF layout: centres on a small patch in front of the still life, all looking at it.
TEST(ForwardScene, CamerasFaceOneWayFromASmallPatch) {
  const std::vector<Camera> cameras = AllCameras(24, 18, 64, 20211202);
  EXPECT_TRUE(CamerasFaceOneWay(cameras));
  // The check tells layouts apart: the capture's loop round the object does not face one way.
  std::vector<Camera> loop;
  for (const View& view : MakeCaptureScene("train", 8, 6, 64, 20211202).views)
    loop.push_back(view.camera);
  EXPECT_FALSE(CamerasFaceOneWay(loop));

  // What the scene is modelled as: auto follows the layout unless the background is white (an
  // object dataset); an explicit type is obeyed whatever the layout.
  EXPECT_TRUE(ModelsForwardFacing(SceneType::kAuto, false, cameras));
  EXPECT_FALSE(ModelsForwardFacing(SceneType::kAuto, true, cameras));
  EXPECT_FALSE(ModelsForwardFacing(SceneType::kAuto, false, loop));
  EXPECT_FALSE(ModelsForwardFacing(SceneType::kUnbounded, false, cameras));
  EXPECT_TRUE(ModelsForwardFacing(SceneType::kForward, true, loop));

  const Vec3 target{kForwardTarget[0], kForwardTarget[1], kForwardTarget[2]};
  Vec3 lo{1e9, 1e9, 1e9}, hi{-1e9, -1e9, -1e9};
  for (const Camera& camera : cameras) {
    const Vec3 c = Centre(camera);
    lo = {std::min(lo.x, c.x), std::min(lo.y, c.y), std::min(lo.z, c.z)};
    hi = {std::max(hi.x, c.x), std::max(hi.y, c.y), std::max(hi.z, c.z)};
    const Vec3 to_target = target - c;
    const double range = std::sqrt(procedural::Dot(to_target, to_target));
    EXPECT_GT(range, 2.3);
    EXPECT_LT(range, 2.7);
    // The optical axis passes within a hand's jitter of the still life's centre.
    const double along = procedural::Dot(to_target, ViewingAxis(camera));
    EXPECT_LT(std::sqrt(range * range - along * along), 0.2);
    EXPECT_GT(ViewingAxis(camera).y, 0.9);  // towards the window wall
  }
  // The patch: about 0.6 m wide, about 0.35 m tall (tilted 15 degrees, so mostly in z).
  EXPECT_GT(hi.x - lo.x, 0.5);
  EXPECT_LT(hi.x - lo.x, 0.7);
  EXPECT_GT(hi.z - lo.z, 0.25);
  EXPECT_LT(hi.z - lo.z, 0.4);
  EXPECT_LT(hi.y - lo.y, 0.25);
}

TEST(ForwardScene, CamerasArePinholesWithAnOffCentrePrincipalPoint) {
  const Dataset scene = MakeForwardScene("test", 120, 90, 16, 1);
  ASSERT_EQ(scene.views.size(), 2u);
  for (const View& view : scene.views) {
    const Camera& c = view.camera;
    EXPECT_EQ(c.width, 120);
    EXPECT_EQ(c.height, 90);
    EXPECT_DOUBLE_EQ(c.fx, FocalFromFieldOfView(120, kCaptureFieldOfView));
    EXPECT_DOUBLE_EQ(c.fy, c.fx);
    EXPECT_DOUBLE_EQ(c.cx, 120 * (0.5 + kCaptureCxOffset));
    EXPECT_DOUBLE_EQ(c.cy, 90 * (0.5 + kCaptureCyOffset));
    EXPECT_GT(std::abs(c.cx - 60.0), 1.0);
    EXPECT_GT(std::abs(c.cy - 45.0), 1.0);
    EXPECT_FALSE(c.HasDistortion());
    EXPECT_EQ(view.rgb.width, 120);
    EXPECT_EQ(view.rgb.height, 90);
    EXPECT_EQ(view.rgb.channels, 3);
  }
  EXPECT_FALSE(scene.white_background);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(scene.scene_aabb[0][a], kCaptureRoomMin[a]);
    EXPECT_EQ(scene.scene_aabb[1][a], kCaptureRoomMax[a]);
  }
}

// The hit distance, checked without it: for the still life, nothing lies between the camera and
// just before the hit and something between the camera and just after it; for the room, the
// hit point is on the room's boundary.
::testing::AssertionResult HitDistanceIsTheSurface(Vec3 o, Vec3 d, double t) {
  constexpr double kDelta = 1e-4;
  if (!(t > 0)) return ::testing::AssertionFailure() << "hit distance " << t;
  if (procedural::StillLifeOccludes(o, d)) {
    if (procedural::StillLifeOccludes(o + d * (t - kDelta), d * -1.0)) {
      return ::testing::AssertionFailure() << "still-life hit at " << t << " is too far";
    }
    if (!procedural::StillLifeOccludes(o + d * (t + kDelta), d * -1.0)) {
      return ::testing::AssertionFailure() << "still-life hit at " << t << " is too near";
    }
    return ::testing::AssertionSuccess();
  }
  const Vec3 p = o + d * t;
  bool inside = true, on_face = false;
  for (int a = 0; a < 3; ++a) {
    const double v = procedural::Axis(p, a);
    inside &= v > kCaptureRoomMin[a] - 1e-9 && v < kCaptureRoomMax[a] + 1e-9;
    on_face |= std::abs(v - kCaptureRoomMin[a]) < 1e-9 || std::abs(v - kCaptureRoomMax[a]) < 1e-9;
  }
  if (!inside || !on_face) {
    return ::testing::AssertionFailure()
           << "room hit " << p.x << "," << p.y << "," << p.z << " is off the walls";
  }
  return ::testing::AssertionSuccess();
}

// LLFF's bounds: far is the deepest surface any pixel sees, near 0.9 of the nearest.
TEST(ForwardScene, NearAndFarBracketEveryPixelsDepth) {
  const int width = 40, height = 30, frames = 16;
  const Dataset scene = MakeForwardScene("train", width, height, frames, 11);
  double lo = INFINITY, hi = 0;
  for (const Camera& camera : AllCameras(width, height, frames, 11)) {
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        float origin[3], dir[3];
        Vec3 o, d;
        PixelRay(camera, x, y, origin, dir, &o, &d);
        const double t = CaptureSceneHitDistance(origin, dir);
        ASSERT_TRUE(HitDistanceIsTheSurface(o, d, t)) << "pixel " << x << "," << y;
        // -z in camera coordinates (to float rounding of the ray origin).
        const double depth = procedural::Dot(o + d * t - Centre(camera), ViewingAxis(camera));
        ASSERT_LE(scene.near, kForwardNearShare * depth + 1e-6) << "pixel " << x << "," << y;
        ASSERT_GE(scene.far, depth - 1e-6) << "pixel " << x << "," << y;
        lo = std::min(lo, depth);
        hi = std::max(hi, depth);
      }
    }
  }
  // Tight: the bounds are the extreme depths, not a guess around them.
  EXPECT_NEAR(scene.near, 0.9 * lo, 1e-6);
  EXPECT_NEAR(scene.far, hi, 1e-6);
  // The still life's front is about 1.5 m away, the window wall about 6 m.
  EXPECT_GT(lo, 1.2);
  EXPECT_LT(lo, 1.8);
  EXPECT_GT(hi, 5.5);
  EXPECT_LT(hi, 7.0);
}

// The still life fills the middle of every frame, and past it the wall 3.2 m behind shows.
TEST(ForwardScene, TheStillLifeIsInFrontOfTheFarWall) {
  const int width = 60, height = 45;
  const Dataset scene = MakeForwardScene("train", width, height, 24, 9);
  for (const View& view : scene.views) {
    int far_wall = 0, centre_object = 0;
    std::set<int> colours;
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        float origin[3], dir[3];
        Vec3 o, d, colour;
        PixelRay(view.camera, x, y, origin, dir, &o, &d);
        const float r = view.rgb.at(x, y, 0), g = view.rgb.at(x, y, 1), b = view.rgb.at(x, y, 2);
        colours.insert(int(r * 15) * 256 + int(g * 15) * 16 + int(b * 15));
        const bool object = procedural::ShadeStillLife(o, d, &colour);
        if (!object) colour = procedural::ShadeRoom(kCaptureRoomMin, kCaptureRoomMax, o, d);
        ASSERT_TRUE(IsWornShade(r, g, b, colour)) << view.name << " at " << x << "," << y;
        if (std::abs(x - width / 2) < 6 && std::abs(y - height / 2) < 5) centre_object += object;
        far_wall += !object && EndsOnTheFarWall(o, d);
      }
    }
    // Gaps between the objects let the odd pixel through.
    EXPECT_GE(centre_object, 11 * 9 * 9 / 10) << view.name << " does not look at the still life";
    EXPECT_GT(far_wall, width * height / 6) << view.name << ": the wall behind is hidden";
    EXPECT_GE(colours.size(), 30u) << view.name << " is too plain";
  }
}

TEST(ForwardScene, TheTrainerLoadsItAsSceneForward) {
  TrainOptions o = PresetOptions("tiny");
  o.procedural_scene = ChoiceFromName<ProceduralScene>("forward", "--scene");
  EXPECT_EQ(o.procedural_scene, ProceduralScene::kForward);
  o.capture_width = 20;
  o.capture_height = 15;
  o.capture_frames = 17;
  const Dataset test = LoadTrainingViews(o, "test");
  ASSERT_EQ(test.views.size(), 3u);  // frames 0, 8, 16
  EXPECT_EQ(test.views[2].name, "forward/frame_016");
  EXPECT_EQ(test.views[2].rgb.width, 20);
  EXPECT_EQ(test.views[2].rgb.pixels,
            MakeForwardScene("test", 20, 15, 17, o.seed).views[2].rgb.pixels);
  EXPECT_TRUE(FitScene(SceneType::kAuto, test).forward_facing);
  EXPECT_THROW(ChoiceFromName<ProceduralScene>("sideways", "--scene"), std::invalid_argument);
  // Forward-facing scenes train with ReLU density, unshifted (TensoRF's LLFF setting); asked for,
  // softplus keeps its shift of -10, as every other scene model has it.
  const TensorfConfig relu = ConfigFor(o, test);
  EXPECT_EQ(relu.density_activation, DensityActivation::kRelu);
  EXPECT_EQ(relu.density_shift, 0.f);
  o.density_activation = DensityActivationChoice::kSoftplus;
  const TensorfConfig softplus = ConfigFor(o, test);
  EXPECT_EQ(softplus.density_activation, DensityActivation::kSoftplus);
  EXPECT_EQ(softplus.density_shift, -10.f);
  o.density_activation = DensityActivationChoice::kAuto;
  o.scene_type = SceneType::kUnbounded;
  EXPECT_EQ(ConfigFor(o, test).density_activation, DensityActivation::kSoftplus);
}

TEST(ForwardScene, IsFastAndRejectsBadArguments) {
  const auto start = std::chrono::steady_clock::now();
  const Dataset train = MakeForwardScene("train", 120, 90, 50, 0);
  const Dataset test = MakeForwardScene("test", 120, 90, 50, 0);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(train.views.size() + test.views.size(), 50u);
  EXPECT_LT(seconds, 2.0);
  EXPECT_THROW(MakeForwardScene("dev", 16, 12, 8, 0), std::runtime_error);
  EXPECT_THROW(MakeForwardScene("train", 0, 12, 8, 0), std::runtime_error);
  EXPECT_THROW(MakeForwardScene("train", 16, 12, 1, 0), std::runtime_error);
}

}  // namespace
}  // namespace ecrf::trainer
