// The state of the ECRF rate objective during training: per-tensor quantization steps (frozen
// when the rate terms switch on, so the trained rate is the rate of the file), the factorized
// entropy model and its optimizer.
#ifndef ECRF_TRAINER_TRAIN_RATE_STATE_H_
#define ECRF_TRAINER_TRAIN_RATE_STATE_H_

#include <vector>

#include "encoder/coded_tensors.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/rate/entropy_model.h"
#include "trainer/rate/rate_objective.h"
#include "trainer/train/adam.h"
#include "trainer/train/train_options.h"

namespace ecrf {
namespace trainer {

// A tensor nearly dead when the rate terms switch on (LLFF flower's y-z density plane with
// TensoRF's LLFF ranks 16,4,4: a peak 11,000x under the x-y plane's) froze a step of its
// peak / 127; its coefficients then regrew past 127 steps, were clamped, and cost 903 KB of a
// 1 MB file at 6.7 bits each while rate control raised lambda_e 2,800x. So no frozen step is
// finer than the largest step of its three siblings (the same grid's planes, or lines) over this
// ratio. With it the same run's file stayed under 0.53 MB at lambda_e 0 before the encoder's
// step search filled the target.
inline constexpr float kStepFloorRatio = 64.f;
// Raises each step to at least the largest of its group of three over kStepFloorRatio; tensors of
// peak 0 (peaks: encoder::PeakCoefficients) neither set nor get the floor.
void FloorNearlyDeadSteps(const std::vector<float>& peaks, std::vector<float>* steps);

struct RateState {
  bool active = false;
  encoder::RateConfig config;
  std::vector<float> steps;  // one per tensor: density planes 0..2, lines 0..2, then appearance
  FactorizedEntropyModel entropy;
  Adam adam;
  // The lambda_e a checkpointed run last trained with (rate control moves it); 0 when unknown.
  float checkpoint_lambda_e = 0.f;
  // The file --target-size's controller measured last (0: none yet), checkpointed with lambda_e.
  size_t rate_control_last_bytes = 0;
  // The coefficient quantizer's rounding offset a checkpointed run trained through.
  float rounding_offset = 0.5f;
  float rdoq_lambda = 0.f;  // ... and its RDOQ lambda (0: none)
  double last_bits = 0.0;   // latest unbiased estimate (bits)
  double last_regularizer = 0.0;

  // Applies the options' block shapes; does not activate.
  void Configure(const TrainOptions& options);
  // Freezes the steps for the model's current grids and initialises the entropy model.
  void Activate(const TensorfModel& model, const TrainOptions& options);
  // Adds lambda_e * dR/dG + lambda_r * d||F(G)||^2/dG to the grid gradients and steps the
  // entropy model. Returns the estimated bits.
  double Step(TensorfModel& model, const TrainOptions& options, uint64_t seed);
  // Deterministic rate of the rounded coefficients under the current entropy model.
  RateReport Evaluate(const TensorfModel& model) const;
};

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_RATE_STATE_H_
