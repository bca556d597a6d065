#include "trainer/train/rate_state.h"

#include <algorithm>
#include <cmath>

#include "encoder/grid_dct.h"
#include "trainer/rate/coded_model.h"

namespace ecrf {
namespace trainer {

void RateState::Configure(const TrainOptions& o) {
  for (int a = 0; a < 3; ++a) {
    config.plane_block[a] = o.plane_block[a];
    config.line_block[a] = o.line_block[a];
  }
}

void FloorNearlyDeadSteps(const std::vector<float>& peaks, std::vector<float>* steps) {
  // Tensors 0..2 planes, 3..5 lines of the density grid, 6..8 and 9..11 the appearance grid's.
  // An all-zero tensor (peak 0) keeps its placeholder step and sets no floor.
  for (size_t first = 0; first + 3 <= steps->size() && first + 3 <= peaks.size(); first += 3) {
    float largest = 0.f;
    for (size_t t = first; t < first + 3; ++t)
      if (peaks[t] > 0.f) largest = std::max(largest, (*steps)[t]);
    for (size_t t = first; t < first + 3; ++t)
      if (peaks[t] > 0.f) (*steps)[t] = std::max((*steps)[t], largest / kStepFloorRatio);
  }
}

void RateState::Activate(const TensorfModel& model, const TrainOptions& o) {
  Configure(o);
  // One block DCT of every tensor gives both the steps and the floor's peaks.
  const std::vector<float> peaks = encoder::PeakCoefficients(DescribeModel(model), config);
  steps = encoder::StepsFromPeaks(peaks, o.coef_bits);
  if (o.quant_step_scale > 0.f) {
    for (float& s : steps) s *= o.quant_step_scale;
  }
  // Tensors 0..5 are the density grid's (coded_tensors.h).
  for (int t = 0; t < 6 && t < static_cast<int>(steps.size()); ++t)
    steps[t] *= o.density_step_factor;
  FloorNearlyDeadSteps(peaks, &steps);
  entropy.Init(NumRateModels(2), o.seed ^ 0x5eedULL);
  adam.Reset(entropy.params().size());
  active = true;
}

double RateState::Step(TensorfModel& model, const TrainOptions& o, uint64_t seed) {
  entropy.ZeroGrads();
  const RateEstimate e =
      AddRateGradients({&model.density(), &model.appearance()}, steps, config, &entropy, o.lambda_e,
                       o.alpha * o.lambda_e, o.rate_fraction, seed);
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
