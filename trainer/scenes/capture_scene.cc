#include "trainer/scenes/capture_scene.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "trainer/data/camera.h"
#include "trainer/scenes/capture_room.h"
#include "trainer/scenes/procedural_math.h"
#include "trainer/scenes/still_life.h"

namespace ecrf::trainer {
namespace {

using procedural::kPi;
using procedural::Normalized;
using procedural::Random;
using procedural::Vec3;

constexpr double kDegree = kPi / 180.0;

// Wear and dirt that never repeat, on the room and the objects alike: the things a phone films
// are not periodic, and photos of periodic ones match wrongly (ecrf prepare posed 22-39 of 50
// full-HD frames of the capture before it had this). Two octaves of value noise, 0.4 m and
// 0.1 m, darken a surface by up to 30 %.
double Wear(Vec3 p) {
  const double n = 0.65 * procedural::ValueNoise(p * (1 / 0.4)) +
                   0.35 * procedural::ValueNoise(p * (1 / 0.1) + Vec3{17.5, 3.25, 9.75});
  return 1.0 - 0.3 * n * n;
}

}  // namespace

Camera CaptureCamera(const procedural::Vec3& position, const procedural::Vec3& target, double roll,
                     double pitch, double yaw, int width, int height) {
  Camera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = FocalFromFieldOfView(width, kCaptureFieldOfView);
  camera.fy = camera.fx;
  camera.cx = width * (0.5 + kCaptureCxOffset);
  camera.cy = height * (0.5 + kCaptureCyOffset);
  camera.k1 = kCaptureK1;
  camera.k2 = kCaptureK2;
  procedural::LookAtPose(position, target, roll, pitch, yaw, camera.c2w);
  return camera;
}

namespace {

// The whole loop, whatever the split, so that train and test frames come from one capture.
std::vector<Camera> CapturePath(int frames, int width, int height, uint32_t seed) {
  Random random(0xca97u ^ (uint64_t{seed} << 20));
  const double phase = 2 * kPi * random.Uniform();
  const double wobble_phase[2] = {2 * kPi * random.Uniform(), 2 * kPi * random.Uniform()};
  std::vector<Camera> cameras;
  for (int i = 0; i < frames; ++i) {
    // Slow swings in distance and height as a person walks round; small per-frame shake.
    const double step = 2 * kPi / frames;
    const double azimuth = phase + step * (i + 0.3 * random.Signed());
    const double loop = step * i;
    const double distance =
        2.5 + 0.25 * std::sin(2 * loop + wobble_phase[0]) + 0.08 * random.Signed();
    const double z = 0.9 + 0.35 * std::sin(3 * loop + wobble_phase[1]) + 0.05 * random.Signed();
    const Vec3 position{distance * std::cos(azimuth), distance * std::sin(azimuth), z};
    const Vec3 target{0.08 * random.Signed(), 0.08 * random.Signed(),
                      -0.15 + 0.08 * random.Signed()};
    const double roll = 3 * kDegree * random.Signed();
    const double pitch = 2 * kDegree * random.Signed();
    const double yaw = 2 * kDegree * random.Signed();
    cameras.push_back(CaptureCamera(position, target, roll, pitch, yaw, width, height));
  }
  return cameras;
}

Image Render(const Camera& camera) {
  Image image = MakeImage(camera.width, camera.height, 3);
  for (int j = 0; j < camera.height; ++j) {
    for (int i = 0; i < camera.width; ++i) {
      float origin[3], dir[3], rgb[3];
      GenerateRay(camera, i, j, origin, dir);
      CaptureSceneRadiance(origin, dir, rgb);
      for (int c = 0; c < 3; ++c) image.at(i, j, c) = rgb[c];
    }
  }
  return image;
}

}  // namespace

void CaptureSceneRadiance(const float origin[3], const float dir[3], float rgb[3]) {
  const Vec3 o{origin[0], origin[1], origin[2]};
  const Vec3 d = Normalized({dir[0], dir[1], dir[2]});
  Vec3 colour;
  // The room is convex and holds both camera and still life, so a still-life hit is always nearer.
  if (!procedural::ShadeStillLife(o, d, &colour)) {
    colour = procedural::ShadeRoom(kCaptureRoomMin, kCaptureRoomMax, o, d);
  }
  colour = colour * Wear(o + d * CaptureSceneHitDistance(origin, dir));
  rgb[0] = static_cast<float>(colour.x);
  rgb[1] = static_cast<float>(colour.y);
  rgb[2] = static_cast<float>(colour.z);
}

double CaptureSceneHitDistance(const float origin[3], const float dir[3]) {
  const Vec3 o{origin[0], origin[1], origin[2]};
  const Vec3 d = Normalized({dir[0], dir[1], dir[2]});
  double t;
  // As in CaptureSceneRadiance: a still-life hit is always nearer than the room.
  if (procedural::StillLifeHitDistance(o, d, &t)) return t;
  return procedural::RoomExitDistance(kCaptureRoomMin, kCaptureRoomMax, o, d);
}

std::vector<View> RenderCaptureFrames(const char* scene, const std::vector<Camera>& cameras,
                                      const std::string& split) {
  std::vector<int> frames;
  for (int i = 0; i < int(cameras.size()); ++i) {
    if ((i % kCaptureTestEvery == 0) == (split != "train")) frames.push_back(i);
  }
  std::vector<View> views(frames.size());
#pragma omp parallel for schedule(dynamic)
  for (int v = 0; v < int(frames.size()); ++v) {
    View& view = views[v];
    view.camera = cameras[frames[v]];
    view.rgb = Render(view.camera);
    char name[64];
    std::snprintf(name, sizeof name, "%s/frame_%03d", scene, frames[v]);
    view.name = name;
  }
  return views;
}

Dataset MakeCaptureScene(const std::string& split, int width, int height, int num_frames,
                         uint32_t seed) {
  procedural::CheckSceneArguments("capture", split, width, height);
  procedural::CheckFrameCount("capture", num_frames);
  const std::vector<Camera> cameras = CapturePath(num_frames, width, height, seed);
  Dataset dataset;
  dataset.white_background = false;
  NgpAabb(kCaptureAabbScale, kNgpDefaultScale, kNgpDefaultOffset, dataset.scene_aabb);
  NearFarFromCameras(cameras, dataset.scene_aabb, &dataset.near, &dataset.far);
  dataset.views = RenderCaptureFrames("capture", cameras, split);
  return dataset;
}

}  // namespace ecrf::trainer
