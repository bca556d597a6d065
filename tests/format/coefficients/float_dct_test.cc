#include "format/coefficients/float_dct.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "format/coefficients/block_shape.h"

namespace ecrf {
namespace {

TEST(FloatDct, MatrixIsOrthonormal) {
  for (int n = 1; n <= 32; n *= 2) {
    const double* m = DctMatrix(n);
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) {
        double dot = 0;
        for (int i = 0; i < n; ++i) dot += m[a * n + i] * m[b * n + i];
        EXPECT_NEAR(dot, a == b ? 1.0 : 0.0, 1e-12);
      }
  }
}

TEST(FloatDct, RoundTripAndEnergyPreservation) {
  std::mt19937 rng(1);
  std::normal_distribution<double> g;
  const int shapes[][3] = {{16, 16, 16}, {1, 8, 8}, {1, 1, 32}, {32, 4, 2}, {1, 1, 1}, {2, 32, 32}};
  for (const auto& d : shapes) {
    const int v = BlockVolume(d);
    std::vector<double> x(v);
    for (auto& e : x) e = g(rng);
    std::vector<double> y = x;
    ForwardDct(y.data(), d);
    double ex = 0, ey = 0;
    for (int i = 0; i < v; ++i) ex += x[i] * x[i], ey += y[i] * y[i];
    EXPECT_NEAR(ex, ey, 1e-9 * ex);
    InverseDct(y.data(), d);
    for (int i = 0; i < v; ++i) ASSERT_NEAR(y[i], x[i], 1e-12);
  }
}

TEST(FloatDct, ConstantBlockHasOnlyDc) {
  const int d[3] = {4, 8, 16};
  std::vector<float> x(512, 2.0f);
  ForwardDct(x.data(), d);
  EXPECT_NEAR(x[0], 2.0 * std::sqrt(512.0), 1e-3);
  for (int i = 1; i < 512; ++i) ASSERT_NEAR(x[i], 0.0f, 1e-4);
}

TEST(FloatDct, InverseIsAdjointOfForward) {
  // <F x, y> == <x, F^T y>: what the trainer relies on to backpropagate through the DCT.
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  const int d[3] = {8, 4, 16};
  std::vector<double> x(512), y(512);
  for (auto& e : x) e = g(rng);
  for (auto& e : y) e = g(rng);
  std::vector<double> fx = x, fty = y;
  ForwardDct(fx.data(), d);
  InverseDct(fty.data(), d);
  double a = 0, b = 0;
  for (int i = 0; i < 512; ++i) a += fx[i] * y[i], b += x[i] * fty[i];
  EXPECT_NEAR(a, b, 1e-9);
}

}  // namespace
}  // namespace ecrf
