#include "decoder/density_activation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "tests/common/marcher_checks.h"
#include "tests/common/naive_renderer.h"

namespace ecrf {
namespace dec {
namespace {

using namespace naive;  // NOLINT(google-build-using-namespace): the reference of every test here

// SPEC.md 7.4: softplus with PyTorch's threshold, or ReLU; the shift is added before either.
TEST(DensityActivation, IsSoftplusOrRelu) {
  EXPECT_EQ(ActivateDensity(DensityActivation::kRelu, -3.f), 0.f);
  EXPECT_EQ(ActivateDensity(DensityActivation::kRelu, -0.f), 0.f);
  EXPECT_EQ(ActivateDensity(DensityActivation::kRelu, 2.5f), 2.5f);
  EXPECT_EQ(ActivateDensity(DensityActivation::kSoftplus, 25.f), 25.f);  // above the threshold
  EXPECT_EQ(ActivateDensity(DensityActivation::kSoftplus, 0.f), std::log1p(1.f));
  EXPECT_GT(ActivateDensity(DensityActivation::kSoftplus, -30.f), 0.f);
}

// ReLU density (HEAD density_activation 1, SPEC.md 7.4): sigma is the shifted feature where it
// is positive and exactly 0 elsewhere; the reference of 7.2 / 7.5 with that sigma, and not the
// softplus image.
TEST(DensityActivation, ReluScenesMatchTheNaiveReference) {
  SceneSpec spec;
  spec.seed = 9;
  TestScene ts;
  BuildScene(spec, &ts);
  ts.field.density_activation = DensityActivation::kRelu;
  ts.field.density_shift = -1.f;
  ExpectMatchesNaive(ts, Exact(), 14);
  RenderOptions no_skip = Exact();
  no_skip.skip_empty_space = false;
  ExpectMatchesNaive(ts, no_skip, 15);

  const Rays rays = MakeRays(ts.field, 16);
  std::vector<float> relu_rgb, relu_acc, softplus_rgb, softplus_acc;
  RenderWith(ts.field, Exact(), rays, &relu_rgb, &relu_acc);
  ts.field.density_activation = DensityActivation::kSoftplus;
  RenderWith(ts.field, Exact(), rays, &softplus_rgb, &softplus_acc);
  double differ = 0.0;
  for (size_t r = 0; r < rays.size(); ++r)
    differ = std::max(differ, double(std::fabs(relu_acc[r] - softplus_acc[r])));
  EXPECT_GT(differ, 0.05);
}

}  // namespace
}  // namespace dec
}  // namespace ecrf
