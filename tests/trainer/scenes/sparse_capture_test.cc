#include "trainer/scenes/sparse_capture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "trainer/data/camera.h"
#include "trainer/scenes/capture_scene.h"

namespace ecrf::trainer {
namespace {

// Pixel (i, j) of `view`, and the radiance along the ray its camera shoots through it.
void PixelAndRadiance(const View& view, int i, int j, float pixel[3], float radiance[3]) {
  float origin[3], dir[3];
  GenerateRay(view.camera, i, j, origin, dir);
  CaptureSceneRadiance(origin, dir, radiance);
  for (int c = 0; c < 3; ++c) pixel[c] = view.rgb.at(i, j, c);
}

TEST(SparseCapture, HoldsOutEveryEighthOfItsFewFrames) {
  const Dataset train = MakeSparseCaptureScene("train", 16, 12, 7);
  const Dataset test = MakeSparseCaptureScene("test", 16, 12, 7);
  ASSERT_EQ(train.views.size(), 21u);
  ASSERT_EQ(test.views.size(), 3u);
  EXPECT_EQ(test.views[0].name, "capture-sparse/frame_000");
  EXPECT_EQ(test.views[2].name, "capture-sparse/frame_016");
  EXPECT_EQ(train.views[0].name, "capture-sparse/frame_001");
  EXPECT_FALSE(train.white_background);
  const Dataset again = MakeSparseCaptureScene("train", 16, 12, 7);
  for (size_t v = 0; v < train.views.size(); ++v)
    EXPECT_EQ(train.views[v].rgb.pixels, again.views[v].rgb.pixels);
}

// Held-out frames show the true colours; training frames the scene's colours times their gain,
// clipped; and the gains differ from frame to frame by up to about a stop.
TEST(SparseCapture, TrainingFramesCarryTheirOwnExposure) {
  const uint32_t seed = 3;
  const Dataset test = MakeSparseCaptureScene("test", 20, 15, seed);
  for (const View& view : test.views) {
    for (int j = 0; j < 15; j += 2) {
      for (int i = 0; i < 20; i += 3) {
        float pixel[3], radiance[3];
        PixelAndRadiance(view, i, j, pixel, radiance);
        for (int c = 0; c < 3; ++c) ASSERT_EQ(pixel[c], radiance[c]);
      }
    }
  }
  const Dataset train = MakeSparseCaptureScene("train", 20, 15, seed);
  float lowest = 10.f, highest = 0.f;
  int frame = 0;
  for (const View& view : train.views) {
    if (++frame % kCaptureTestEvery == 0) ++frame;  // the frame index of this view
    float gain[3];
    SparseCaptureGain(frame, seed, gain);
    for (int c = 0; c < 3; ++c) {
      lowest = std::min(lowest, gain[c]);
      highest = std::max(highest, gain[c]);
    }
    for (int j = 0; j < 15; j += 2) {
      for (int i = 0; i < 20; i += 3) {
        float pixel[3], radiance[3];
        PixelAndRadiance(view, i, j, pixel, radiance);
        for (int c = 0; c < 3; ++c) ASSERT_EQ(pixel[c], std::min(1.f, radiance[c] * gain[c]));
      }
    }
  }
  EXPECT_LT(lowest, 0.85f);
  EXPECT_GT(highest, 1.15f);
  EXPECT_GT(highest, 1.5f * lowest);
  float unit[3];
  SparseCaptureGain(8, seed, unit);
  EXPECT_EQ(unit[0], 1.f);
}

// The walk round the object crowds on one side: neighbouring frames are far more apart in
// azimuth on the other.
TEST(SparseCapture, CoverageIsUneven) {
  const Dataset train = MakeSparseCaptureScene("train", 16, 12, 11);
  const Dataset test = MakeSparseCaptureScene("test", 16, 12, 11);
  std::vector<double> azimuth;
  for (const Dataset* d : {&train, &test}) {
    for (const View& v : d->views)
      azimuth.push_back(std::atan2(v.camera.c2w[1][3], v.camera.c2w[0][3]));
  }
  std::sort(azimuth.begin(), azimuth.end());
  std::vector<double> gaps;
  for (size_t k = 0; k < azimuth.size(); ++k) {
    const double next = k + 1 < azimuth.size() ? azimuth[k + 1] : azimuth[0] + 2 * M_PI;
    gaps.push_back(next - azimuth[k]);
  }
  const double widest = *std::max_element(gaps.begin(), gaps.end());
  const double narrowest = *std::min_element(gaps.begin(), gaps.end());
  EXPECT_GT(widest, 2 * M_PI / 24 * 1.4);
  EXPECT_GT(widest, 2.5 * narrowest);
}

}  // namespace
}  // namespace ecrf::trainer
