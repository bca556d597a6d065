// `ecrf report sensitivity`: the cost of each tensor's quantization noise is what rendering pays
// for it (zero where nothing is coded, quadratic in the noise), and the balanced steps keep the
// rate while equalising the slopes.
#include "tools/report/quant_sensitivity.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "tests/common/small_model.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/quant_aware.h"

namespace ecrf {
namespace tools {
namespace {

trainer::TensorfModel SmallModel() { return testing_models::DenseSmallModel(); }

encoder::RateConfig SmallBlocks() { return testing_models::SmallRateBlocks(); }

// The steps of the float model, kept for its decoded copy (whose peaks differ), as training
// freezes them.
const std::vector<float>& Steps() {
  static const std::vector<float> steps = [] {
    std::vector<float> s = trainer::ChooseQuantSteps(SmallModel(), SmallBlocks(), 8);
    for (float& v : s) v *= 4.f;  // coarse: most coefficients at level 0, as in trained runs
    return s;
  }();
  return steps;
}

constexpr int kMlpMaxLevel = 7;

// The model as its own file decodes it (tools::DecodedModel): quantizing it again changes
// nothing, so its renders are the targets of a model at its optimum, where every perturbation
// costs (the curvature that the measurement reads is positive, as at the end of a training run).
trainer::TensorfModel Decoded(const trainer::TensorfModel& model) {
  return DecodedModel(model, Steps(), SmallBlocks(), kMlpMaxLevel);
}

struct Rays {
  int n = 1024;
  std::vector<float> origins, dirs, rgb;
};

// Rays from a sphere of radius 3 into the box; targets: the model's colours.
Rays MakeRays(const trainer::TensorfModel& model) {
  Rays r;
  testing_models::RaysFromSphere(r.n, 11, &r.origins, &r.dirs);
  r.rgb.resize(static_cast<size_t>(r.n) * 3);
  trainer::RenderRays(model, r.n, r.origins.data(), r.dirs.data(), r.rgb.data(), nullptr);
  return r;
}

SensitivityReport Measure(const trainer::TensorfModel& model, double noise_scale = 1.0,
                          uint64_t seed = 3) {
  static const Rays rays = MakeRays(Decoded(SmallModel()));
  return MeasureQuantSensitivity(model, Steps(), SmallBlocks(), kMlpMaxLevel, rays.n,
                                 rays.origins.data(), rays.dirs.data(), rays.rgb.data(), seed,
                                 noise_scale);
}

TEST(QuantSensitivity, EveryCodedTensorCostsAndAnUncodedOneNothing) {
  const SensitivityReport r = Measure(Decoded(SmallModel()));
  ASSERT_EQ(r.tensors.size(), 12u);
  EXPECT_EQ(r.mse, 0.0);  // the targets are its own renders
  for (const TensorSensitivity& s : r.tensors) {
    ASSERT_GT(s.nonzero, 0) << s.name;
    EXPECT_GT(s.dmse, 0.0) << s.name;
    EXPECT_GE(s.mean_abs_level, 1.0) << s.name;
  }
  trainer::TensorfModel model = SmallModel();
  float* line = model.appearance().line(0);
  std::fill(line, line + model.appearance().line_size(0), 0.f);
  const SensitivityReport z = Measure(model);
  const TensorSensitivity& zero = z.tensors[9];
  EXPECT_EQ(zero.name, "appearance.line.0");
  EXPECT_EQ(zero.nonzero, 0);
  EXPECT_EQ(zero.dmse, 0.0);
  EXPECT_EQ(zero.balanced_step, zero.step);
  // Mode 0's products are plane 0 times line 0: with the line at zero its plane cannot show.
  EXPECT_EQ(z.tensors[6].name, "appearance.plane.0");
  EXPECT_EQ(z.tensors[6].dmse, 0.0);
}

// The antithetic pair cancels the first-order term: half the noise costs a quarter (for noise
// small enough that the second-order term dominates).
TEST(QuantSensitivity, TheCostIsQuadraticInTheNoise) {
  const trainer::TensorfModel model = Decoded(SmallModel());
  const SensitivityReport full = Measure(model, 0.04), half = Measure(model, 0.02);
  int checked = 0;
  for (size_t t = 0; t < full.tensors.size(); ++t) {
    if (full.tensors[t].nonzero == 0) continue;
    ++checked;
    const double ratio = full.tensors[t].dmse / half.tensors[t].dmse;
    EXPECT_GT(ratio, 3.0) << full.tensors[t].name;
    EXPECT_LT(ratio, 5.0) << full.tensors[t].name;
  }
  EXPECT_GE(checked, 6);
}

TEST(QuantSensitivity, BalancedStepsKeepTheRateAndEqualiseTheSlopes) {
  const SensitivityReport r = Measure(Decoded(SmallModel()));
  double rate_change = 0.0, lo = 1e300, hi = 0.0;
  for (const TensorSensitivity& s : r.tensors) {
    if (s.nonzero == 0) continue;
    const double k = double(s.balanced_step) / s.step;
    rate_change += static_cast<double>(s.nonzero) * std::log(k);
    const double slope_after = s.slope * k * k;  // D scales with step^2
    lo = std::min(lo, slope_after);
    hi = std::max(hi, slope_after);
  }
  EXPECT_NEAR(rate_change, 0.0, 1e-3);
  EXPECT_LT(hi / lo, 1.0 + 1e-4);
  EXPECT_LE(r.balanced_quant_mse, r.quant_mse * (1.0 + 1e-12));
}

TEST(QuantSensitivity, TheSameSeedMeasuresTheSame) {
  const trainer::TensorfModel model = SmallModel();
  const SensitivityReport a = Measure(model, 1.0, 9), b = Measure(model, 1.0, 9);
  for (size_t t = 0; t < a.tensors.size(); ++t) EXPECT_EQ(a.tensors[t].dmse, b.tensors[t].dmse);
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
