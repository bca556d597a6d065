#include "trainer/data/image_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <stdexcept>

namespace ecrf::trainer {
namespace {

Image Pattern(int width, int height, int channels,
              const std::function<float(int, int, int)>& value) {
  Image image = MakeImage(width, height, channels);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < channels; ++c) image.at(x, y, c) = value(x, y, c);
    }
  }
  return image;
}

// Deterministic noise in [-amplitude, amplitude].
Image AddNoise(const Image& image, float amplitude, uint32_t seed) {
  Image noisy = image;
  uint32_t state = seed;
  for (float& v : noisy.pixels) {
    state = state * 1664525u + 1013904223u;
    v += amplitude * (static_cast<float>(state >> 8) / 8388608.0f - 1.0f);
  }
  return noisy;
}

float PatternA(int x, int y, int c) { return ((x * 7 + y * 3 + c * 5) % 11) / 10.0f; }

TEST(Psnr, KnownValues) {
  const Image a = MakeImage(8, 8, 3, 0.5f);
  EXPECT_NEAR(Psnr(a, MakeImage(8, 8, 3, 0.6f)), 20.0, 1e-5);   // MSE 0.01
  EXPECT_NEAR(Psnr(a, MakeImage(8, 8, 3, 0.51f)), 40.0, 1e-3);  // MSE 1e-4
  EXPECT_EQ(Psnr(a, a), std::numeric_limits<double>::infinity());
  // One channel of one pixel off by 1 in a 2x2 RGB image: MSE 1/12.
  Image b = MakeImage(2, 2, 3, 0.0f);
  Image c = b;
  c.at(1, 1, 2) = 1.0f;
  EXPECT_NEAR(Psnr(b, c), 10 * std::log10(12.0), 1e-9);
  EXPECT_DOUBLE_EQ(Psnr(b, c), Psnr(c, b));
}

TEST(Psnr, IgnoresAlphaAndChecksShapes) {
  Image a = MakeImage(4, 4, 4, 0.5f);
  Image b = a;
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 4; ++x) b.at(x, y, 3) = 0.0f;
  }
  EXPECT_EQ(Psnr(a, b), std::numeric_limits<double>::infinity());
  EXPECT_THROW(Psnr(a, MakeImage(4, 5, 4)), std::runtime_error);
  EXPECT_THROW(Psnr(a, MakeImage(4, 4, 3)), std::runtime_error);
}

TEST(Ssim, IdenticalImagesGiveOne) {
  const Image a = Pattern(20, 16, 3, PatternA);
  EXPECT_DOUBLE_EQ(Ssim(a, a), 1.0);
}

TEST(Ssim, ConstantImagesOnlyCompareMeans) {
  // No variance anywhere: SSIM = (2 mu_a mu_b + C1) / (mu_a^2 + mu_b^2 + C1).
  const double c1 = 1e-4;
  const double expected = (2 * 0.5 * 0.25 + c1) / (0.25 + 0.0625 + c1);
  EXPECT_NEAR(Ssim(MakeImage(11, 11, 3, 0.5f), MakeImage(11, 11, 3, 0.25f)), expected, 1e-12);
  EXPECT_NEAR(Ssim(MakeImage(30, 12, 3, 0.5f), MakeImage(30, 12, 3, 0.25f)), expected, 1e-12);
}

TEST(Ssim, SingleWindowAgainstHandComputedGaussianWeight) {
  // An 11x11 image has exactly one valid window. A lone 1 at the centre gives
  // mu = w^2 and E[x^2] = w^2 where w is the centre tap of the normalised 1D Gaussian.
  double sum = 0;
  for (int i = -5; i <= 5; ++i) sum += std::exp(-0.5 * (i / 1.5) * (i / 1.5));
  const double w2 = 1.0 / (sum * sum);
  const double c1 = 1e-4, c2 = 9e-4;
  const double mu = w2, var = w2 - w2 * w2;
  // Against black: mu_b = var_b = cov = 0.
  const double expected = c1 * c2 / ((mu * mu + c1) * (var + c2));
  const Image dot =
      Pattern(11, 11, 1, [](int x, int y, int) { return x == 5 && y == 5 ? 1.0f : 0.0f; });
  EXPECT_NEAR(Ssim(dot, MakeImage(11, 11, 1, 0.0f)), expected, 1e-12);
}

TEST(Ssim, MatchesTensorfReferenceValues) {
  // Values from a literal Python transcription of TensoRF's rgb_ssim on the same patterns.
  const Image a = Pattern(17, 13, 3, PatternA);
  const Image uncorrelated = Pattern(
      17, 13, 3, [](int x, int y, int c) { return ((x * 5 + y * 2 + c * 3) % 13) / 12.0f; });
  const Image similar = Pattern(17, 13, 3, [](int x, int y, int c) {
    return 0.8f * PatternA(x, y, c) + 0.1f + 0.05f * ((x * y + c) % 3) / 2.0f;
  });
  // float pixels vs Python doubles: agreement to ~1e-7.
  EXPECT_NEAR(Ssim(a, uncorrelated), -0.013720587595936874, 1e-6);
  EXPECT_NEAR(Ssim(a, similar), 0.9749694694713803, 1e-6);
}

TEST(Ssim, IsSymmetricAndDropsWithNoise) {
  const Image a = Pattern(32, 24, 3, PatternA);
  const Image b = AddNoise(a, 0.05f, 1);
  EXPECT_DOUBLE_EQ(Ssim(a, b), Ssim(b, a));
  double previous = 1.0;
  for (float amplitude : {0.02f, 0.1f, 0.3f}) {
    const double value = Ssim(a, AddNoise(a, amplitude, 7));
    EXPECT_LT(value, previous) << amplitude;
    previous = value;
  }
  EXPECT_GT(Ssim(a, AddNoise(a, 0.02f, 7)), 0.9);
}

TEST(Ssim, RejectsSmallOrMismatchedImages) {
  EXPECT_THROW(Ssim(MakeImage(10, 20, 3), MakeImage(10, 20, 3)), std::runtime_error);
  EXPECT_THROW(Ssim(MakeImage(20, 20, 3), MakeImage(20, 21, 3)), std::runtime_error);
}

}  // namespace
}  // namespace ecrf::trainer
