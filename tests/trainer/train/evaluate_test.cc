// Scoring held-out views (trainer/train/evaluate.h): the half-image protocol's exposure fit uses
// the left half of a view only, and scores the right half with the gain it found.
#include "trainer/train/evaluate.h"

#include <gtest/gtest.h>

#include <random>

#include "trainer/data/image_metrics.h"

namespace ecrf {
namespace trainer {
namespace {

Image RandomImage(int w, int h, float lo, float hi, uint32_t seed) {
  Image img;
  img.width = w;
  img.height = h;
  img.channels = 3;
  img.pixels.resize(size_t(w) * h * 3);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(lo, hi);
  for (float& p : img.pixels) p = u(rng);
  return img;
}

View ViewOf(const Image& truth) {
  View v;
  v.rgb = truth;
  v.name = "v";
  return v;
}

// A render darker than its photo by a gain per channel (the exposure the file leaves out): the
// fit finds the gains on the left half, and the right half then scores as exact.
TEST(EvaluateTest, TheExposureFitFindsEachChannelsGainOnTheLeftHalf) {
  const Image truth = RandomImage(40, 30, 0.02f, 0.7f, 3);
  const float gain[3] = {1.3f, 0.8f, 1.1f};
  Image render = truth;
  for (size_t i = 0; i < render.pixels.size(); ++i) render.pixels[i] /= gain[i % 3];
  float fitted[3];
  FitExposureGain(render, truth, 20, fitted);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(fitted[c], gain[c], 1e-5f) << c;

  EvalResult neutral, half;
  AddViewScore(render, ViewOf(truth), &neutral);
  const Dataset marked = WithExposureFit(Dataset{{ViewOf(truth)}});
  ASSERT_EQ(marked.views[0].fitted_columns, 20);
  ASSERT_TRUE(marked.views[0].fit_exposure);
  AddViewScore(render, marked.views[0], &half);
  EXPECT_LT(neutral.psnr, 25.0);
  EXPECT_GT(half.psnr, 90.0);
  EXPECT_TRUE(half.exposure_fitted);
  EXPECT_FALSE(neutral.exposure_fitted);
  EXPECT_EQ(half.fitted_columns, 20);
}

// No scored pixel fits anything: spoiling the photo's right half changes the score but not the
// gain, and spoiling its left half changes the gain.
TEST(EvaluateTest, TheScoredRightHalfDoesNotFitTheGain) {
  const Image truth = RandomImage(32, 16, 0.1f, 0.6f, 5);
  const Image render = RandomImage(32, 16, 0.1f, 0.6f, 6);
  Image right_spoilt = truth, left_spoilt = truth;
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) {
      for (int c = 0; c < 3; ++c) {
        right_spoilt.pixels[(size_t(y) * 32 + 16 + x) * 3 + c] = 1.f;
        left_spoilt.pixels[(size_t(y) * 32 + x) * 3 + c] = 1.f;
      }
    }
  }
  float g[3], g_right[3], g_left[3];
  FitExposureGain(render, truth, 16, g);
  FitExposureGain(render, right_spoilt, 16, g_right);
  FitExposureGain(render, left_spoilt, 16, g_left);
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(g[c], g_right[c]);
    EXPECT_GT(g_left[c], g[c] * 1.2f);
  }
  EvalResult a, b;
  AddViewScore(render, WithExposureFit(Dataset{{ViewOf(truth)}}).views[0], &a);
  AddViewScore(render, WithExposureFit(Dataset{{ViewOf(right_spoilt)}}).views[0], &b);
  EXPECT_NE(a.psnr, b.psnr);
}

// A view whose camera was aligned on more than half keeps its own fitted columns; gains are
// clipped at 1 as a photo is, and a black left half leaves the gain at 1.
TEST(EvaluateTest, TheFitKeepsWiderFittedColumnsAndClipsAtOne) {
  const Image truth = RandomImage(30, 12, 0.5f, 1.f, 9);
  View aligned = ViewOf(truth);
  aligned.fitted_columns = 18;
  EXPECT_EQ(WithExposureFit(Dataset{{aligned}}).views[0].fitted_columns, 18);
  Image black = truth;
  for (float& p : black.pixels) p = 0.f;
  float g[3];
  FitExposureGain(black, truth, 15, g);
  for (int c = 0; c < 3; ++c) EXPECT_EQ(g[c], 1.f);
  // The render at half brightness: the fitted gain 2 would push the bright pixels past 1.
  Image dim = truth;
  for (float& p : dim.pixels) p *= 0.5f;
  EvalResult r;
  AddViewScore(dim, WithExposureFit(Dataset{{ViewOf(truth)}}).views[0], &r);
  EXPECT_GT(r.psnr, 90.0);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
