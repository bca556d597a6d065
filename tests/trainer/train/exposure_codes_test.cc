#include "trainer/train/exposure_codes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace ecrf {
namespace trainer {
namespace {

// Frames of one scene taken at different exposures: view v's pixels are true_gain[v] x C (clipped
// at 1). Fitting the codes to the squared error must find the gains while the gauge holds.
TEST(ExposureCodesTest, RecoversPerViewGainsAndKeepsTheirGeometricMeanNeutral) {
  const int views = 6, rays = 4000, batch = 256;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> stops(-0.5f, 0.5f), radiance(0.05f, 0.9f);
  std::vector<float> true_log(3 * views);
  for (auto& g : true_log) g = stops(rng) * std::log(2.f);
  // C stays fixed here (in training the field takes up the common factor), so the true gains
  // get the neutral exposure the gauge keeps: each channel's mean log gain 0.
  for (int ch = 0; ch < 3; ++ch) {
    float mean = 0.f;
    for (int v = 0; v < views; ++v) mean += true_log[3 * v + ch] / views;
    for (int v = 0; v < views; ++v) true_log[3 * v + ch] -= mean;
  }
  std::vector<uint32_t> ray_view(rays);
  std::vector<float> c(3 * rays), target(3 * rays);
  for (int r = 0; r < rays; ++r) {
    ray_view[r] = static_cast<uint32_t>(r % views);
    for (int ch = 0; ch < 3; ++ch) {
      c[3 * r + ch] = radiance(rng);
      target[3 * r + ch] = std::min(1.f, std::exp(true_log[3 * (r % views) + ch]) * c[3 * r + ch]);
    }
  }
  ExposureCodes codes;
  codes.Reset(views);
  ASSERT_TRUE(codes.enabled());
  std::vector<uint32_t> bv(batch);
  std::vector<float> gains(3 * batch), grad(3 * batch);
  std::uniform_int_distribution<int> pick(0, rays - 1);
  for (int step = 0; step < 1500; ++step) {
    std::vector<int> idx(batch);
    for (int i = 0; i < batch; ++i) {
      idx[i] = pick(rng);
      bv[i] = ray_view[idx[i]];
    }
    codes.Gains(batch, bv.data(), gains.data());
    for (int i = 0; i < batch; ++i) {
      for (int ch = 0; ch < 3; ++ch) {
        const float ci = c[3 * idx[i] + ch], pixel = gains[3 * i + ch] * ci;
        const float diff = std::min(pixel, 1.f) - target[3 * idx[i] + ch];
        grad[3 * i + ch] = pixel <= 1.f ? 2.f * diff * ci / (3.f * batch) : 0.f;
      }
    }
    codes.Step(batch, bv.data(), gains.data(), grad.data(), step < 1000 ? 1e-2f : 1e-3f);
  }
  for (int ch = 0; ch < 3; ++ch) {
    double learnt_mean = 0.0;
    for (int v = 0; v < views; ++v) learnt_mean += codes.log_gain()[3 * v + ch] / views;
    EXPECT_NEAR(learnt_mean, 0.0, 1e-6) << "channel " << ch;
    for (int v = 0; v < views; ++v) {
      EXPECT_NEAR(codes.log_gain()[3 * v + ch], true_log[3 * v + ch], 0.01)
          << "view " << v << " channel " << ch;
    }
  }
}

TEST(ExposureCodesTest, StartsNeutralAndRefusesUnknownViews) {
  ExposureCodes codes;
  EXPECT_FALSE(codes.enabled());
  codes.Reset(2);
  EXPECT_EQ(codes.views(), 2);
  const uint32_t views[2] = {1, 0};
  float gains[6];
  codes.Gains(2, views, gains);
  for (float g : gains) EXPECT_EQ(g, 1.f);
  const uint32_t bad[1] = {2};
  EXPECT_THROW(codes.Gains(1, bad, gains), std::out_of_range);
  EXPECT_THROW(codes.Reset(-1), std::invalid_argument);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
