#include "trainer/scenes/sparse_capture.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "trainer/data/camera.h"
#include "trainer/scenes/capture_scene.h"
#include "trainer/scenes/procedural_math.h"

namespace ecrf::trainer {
namespace {

using procedural::kPi;
using procedural::Random;
using procedural::Vec3;

constexpr double kDegree = kPi / 180.0;
// Azimuth(u) = 2 pi (u + kCrowding sin(2 pi u) / (2 pi)): its slope, the spacing of frames,
// runs from 1 - kCrowding to 1 + kCrowding of the even spacing (4:1 for 0.6).
constexpr double kCrowding = 0.6;
constexpr double kExposureStops = 0.5;  // gain 2^U(-0.5, 0.5)
constexpr double kTint = 0.06;          // per channel, times 1 + U(-0.06, 0.06)

std::vector<Camera> SparsePath(int frames, int width, int height, uint32_t seed) {
  Random random(0x5a75e1u ^ (uint64_t{seed} << 20));
  const double phase = 2 * kPi * random.Uniform();
  std::vector<Camera> cameras;
  for (int i = 0; i < frames; ++i) {
    const double u = (i + 0.2 * random.Signed()) / frames;
    const double azimuth = phase + 2 * kPi * u + kCrowding * std::sin(2 * kPi * u);
    const double distance = 2.5 + 0.3 * std::sin(4 * kPi * u) + 0.08 * random.Signed();
    const double z = 0.9 + 0.35 * std::sin(6 * kPi * u + 1.0) + 0.05 * random.Signed();
    const Vec3 position{distance * std::cos(azimuth), distance * std::sin(azimuth), z};
    const Vec3 target{0.08 * random.Signed(), 0.08 * random.Signed(),
                      -0.15 + 0.08 * random.Signed()};
    cameras.push_back(CaptureCamera(position, target, 3 * kDegree * random.Signed(),
                                    2 * kDegree * random.Signed(), 2 * kDegree * random.Signed(),
                                    width, height));
  }
  return cameras;
}

}  // namespace

void SparseCaptureGain(int frame, uint32_t seed, float gain[3]) {
  if (frame % kCaptureTestEvery == 0) {
    gain[0] = gain[1] = gain[2] = 1.f;
    return;
  }
  Random random((uint64_t{seed} << 32) ^ (0xe8f05u + static_cast<uint64_t>(frame) * 7919u));
  const double exposure = std::exp2(kExposureStops * random.Signed());
  for (int c = 0; c < 3; ++c)
    gain[c] = static_cast<float>(exposure * (1 + kTint * random.Signed()));
}

Dataset MakeSparseCaptureScene(const std::string& split, int width, int height, uint32_t seed) {
  procedural::CheckSceneArguments("capture-sparse", split, width, height);
  const std::vector<Camera> cameras = SparsePath(kSparseCaptureFrames, width, height, seed);
  Dataset dataset;
  dataset.white_background = false;
  NgpAabb(kCaptureAabbScale, kNgpDefaultScale, kNgpDefaultOffset, dataset.scene_aabb);
  NearFarFromCameras(cameras, dataset.scene_aabb, &dataset.near, &dataset.far);
  dataset.views = RenderCaptureFrames("capture-sparse", cameras, split);
  // RenderCaptureFrames keeps the frames of the split in increasing order.
  std::vector<int> frames;
  for (int i = 0; i < kSparseCaptureFrames; ++i) {
    if ((i % kCaptureTestEvery == 0) == (split != "train")) frames.push_back(i);
  }
  for (size_t v = 0; v < dataset.views.size(); ++v) {
    float gain[3];
    SparseCaptureGain(frames[v], seed, gain);
    Image& image = dataset.views[v].rgb;
    for (int j = 0; j < image.height; ++j) {
      for (int i = 0; i < image.width; ++i) {
        for (int c = 0; c < 3; ++c) image.at(i, j, c) = std::min(1.f, image.at(i, j, c) * gain[c]);
      }
    }
  }
  return dataset;
}

}  // namespace ecrf::trainer
