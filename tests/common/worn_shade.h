// The capture's surfaces are worn (capture_scene.cc): each pixel is the surface's own shade, as
// ShadeStillLife or ShadeRoom give it, darkened by one factor in [0.7, 1] for all three channels.
#ifndef ECRF_TESTS_COMMON_WORN_SHADE_H_
#define ECRF_TESTS_COMMON_WORN_SHADE_H_

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "trainer/scenes/procedural_math.h"

namespace ecrf::trainer {

// The factor a pixel's brightest channel is of the surface's own shade.
inline double WearOf(float r, float g, float b, procedural::Vec3 shade) {
  const double brightest = std::max({shade.x, shade.y, shade.z});
  return brightest > 0 ? std::max({r, g, b}) / brightest : 1.0;
}

inline ::testing::AssertionResult IsWornShade(float r, float g, float b, procedural::Vec3 shade) {
  const double wear = WearOf(r, g, b, shade);
  const double channels[3][2] = {{r, shade.x}, {g, shade.y}, {b, shade.z}};
  bool alike = wear >= 0.7 - 1e-6 && wear <= 1 + 1e-6;
  for (const auto& [seen, own] : channels) alike = alike && std::abs(seen - own * wear) < 2e-6;
  if (alike) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "pixel (" << r << ", " << g << ", " << b << ") is not (" << shade.x << ", " << shade.y
         << ", " << shade.z << ") darkened by one factor in [0.7, 1]";
}

}  // namespace ecrf::trainer

#endif  // ECRF_TESTS_COMMON_WORN_SHADE_H_
