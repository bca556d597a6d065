#include "trainer/rate_state.h"

#include <algorithm>
#include <cmath>

#include "trainer/grid_dct.h"

namespace ecrf {
namespace trainer {

const char* RateTensorName(int t) {
  static const char* kNames[12] = {
      "density.plane.0",    "density.plane.1",    "density.plane.2",    "density.line.0",
      "density.line.1",     "density.line.2",     "appearance.plane.0", "appearance.plane.1",
      "appearance.plane.2", "appearance.line.0",  "appearance.line.1",  "appearance.line.2"};
  return t >= 0 && t < 12 ? kNames[t] : "?";
}

std::vector<float> PeakCoefficients(const TensorfModel& model, const RateConfig& config) {
  std::vector<float> peaks;
  for (const VmGrid* grid : {&model.density(), &model.appearance()}) {
    for (int t = 0; t < kTensorsPerGrid; ++t) {
      const GridBlockLayout layout = RateTensorLayout(*grid, t, config);
      std::vector<float> coeffs(layout.num_coeffs());
      ForwardBlocks(RateTensorData(*grid, t), layout, coeffs.data());
      float peak = 0.f;
      for (float c : coeffs) peak = std::max(peak, std::fabs(c));
      peaks.push_back(peak);
    }
  }
  return peaks;
}

std::vector<float> ChooseQuantSteps(const TensorfModel& model, const RateConfig& config, int coef_bits) {
  const float max_level = coef_bits == 16 ? 32767.f : 127.f;
  std::vector<float> steps = PeakCoefficients(model, config);
  // An all-zero tensor still needs a positive step; any value codes it as zeros.
  for (float& s : steps) s = s > 0.f ? s / max_level : 1.f;
  return steps;
}

void RateState::Configure(const TrainOptions& o) {
  for (int a = 0; a < 3; ++a) {
    config.plane_block[a] = o.plane_block[a];
    config.line_block[a] = o.line_block[a];
  }
}

void RateState::Activate(const TensorfModel& model, const TrainOptions& o) {
  Configure(o);
  steps = ChooseQuantSteps(model, config, o.coef_bits);
  if (o.quant_step_scale > 0.f) {
    for (float& s : steps) s *= o.quant_step_scale;
  }
  entropy.Init(NumRateModels(2), o.seed ^ 0x5eedULL);
  adam.Reset(entropy.params().size());
  active = true;
}

double RateState::Step(TensorfModel& model, const TrainOptions& o, uint64_t seed) {
  entropy.ZeroGrads();
  const RateEstimate e = AddRateGradients({&model.density(), &model.appearance()}, steps, config,
                                          &entropy, o.lambda_e, o.alpha * o.lambda_e, o.rate_fraction, seed);
  adam.Step(entropy.params().data(), entropy.grads().data(), entropy.params().size(), o.entropy_lr);
  last_bits = e.bits;
  last_regularizer = e.regularizer;
  return e.bits;
}

RateReport RateState::Evaluate(const TensorfModel& model) const {
  return EvaluateRate({&model.density(), &model.appearance()}, steps, config, entropy);
}

}  // namespace trainer
}  // namespace ecrf
