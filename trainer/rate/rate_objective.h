// Rate term of the ECRF training loss: the feature grids are transformed by the block DCT
// (encoder/grid_dct.h), divided by a per-tensor quantization step, and coded under a factorized
// entropy model (trainer/rate/entropy_model.h).
//
// Tensors: grid g (0 = density, 1 = appearance by convention; any number of grids), tensor t in
// 0..5 = planes 0..2 then lines 0..2 (the VmGrid flat order); tensor index = g * 6 + t.
// Model grouping: one entropy model per (tensor, frequency band), model index
// = tensor_index * kNumFrequencyBands + band, band = 6 * Octave(kc) + Octave(ks) where kc is the
// coefficient's frequency along the channel axis and ks the sum of its spatial frequencies
// (planes: kc = k0, ks = k1 + k2; lines: kc = k1, ks = k2), Octave(s) = 0, 1, 2 for s = 0, 1,
// 2-3, ... capped at 5 (16+). Measured on a trained (tiny, 100^3) checkpoint with rounded
// coefficients and per-group trained models, bits per value vs alternatives: one model per tensor
// +5-25%; 8 octave bands of k0+k1+k2 (channel frequency mixed with spatial) +2-4% on
// appearance planes, +5-10% on density planes, +10-20% on lines; per-position models for the
// low frequencies: -5% on density planes, +2% on appearance planes. Channels are not a
// stationary axis, so the channel frequency is kept apart from the spatial ones.
#ifndef ECRF_TRAINER_RATE_RATE_OBJECTIVE_H_
#define ECRF_TRAINER_RATE_RATE_OBJECTIVE_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "encoder/grid_dct.h"
#include "trainer/model/vm_grid.h"
#include "trainer/rate/coded_model.h"
#include "trainer/rate/entropy_model.h"

namespace ecrf {
namespace trainer {

inline constexpr int kNumFrequencyBands = 36;

// 0 for s = 0, else min(5, 1 + floor(log2(s))).
int FrequencyOctave(int s);
// Band of the coefficient at in-block frequency (k0, k1, k2) of a plane (line = false) or line
// block: 6 * FrequencyOctave(kc) + FrequencyOctave(ks), see above.
int FrequencyBand(bool line, int k0, int k1, int k2);
inline int RateModelIndex(int tensor_index, int band) {
  return tensor_index * kNumFrequencyBands + band;
}
inline int NumRateModels(int num_grids) {
  return num_grids * encoder::kTensorsPerGrid * kNumFrequencyBands;
}

struct RateEstimate {
  double bits = 0.0;         // unbiased estimate of the total noisy-proxy bits (all tensors)
  double regularizer = 0.0;  // unbiased estimate of sum of squared DCT coefficients (unweighted)
};

// Stochastic rate term for one training step. For every tensor, a random subset of
// k = max(1, round(fraction * N)) of its N blocks (without replacement; all when fraction >= 1)
// is transformed; x = coeff / step + U(-1/2, 1/2) (noise hashed from seed, tensor, block,
// position) is coded under the tensor's band models, and the per-tensor sums are scaled by N / k
// (unbiased for the full-grid sums). Adds into grids[g]->grads():
//   lambda_e * d(bits estimate)/dG + lambda_r * d(regularizer estimate)/dG,
// adds d(bits estimate)/d(model params) (NOT multiplied by lambda_e) into model->grads(), and
// returns the unweighted estimates. steps: num_grids * 6 quantization steps (> 0).
// model->num_models() must be >= NumRateModels(grids.size()).
RateEstimate AddRateGradients(const std::vector<VmGrid*>& grids, const std::vector<float>& steps,
                              const encoder::RateConfig& config, FactorizedEntropyModel* model,
                              float lambda_e, float lambda_r, float fraction, uint64_t seed);

// Full deterministic evaluation: all blocks, x = round(coeff / step) (std::round, half away
// from zero), no noise, no gradients: the bits an encoder using this static model would pay
// (up to the arithmetic coder's overhead).
struct RateReport {
  std::vector<double> bits;    // per tensor index
  std::vector<size_t> coeffs;  // coefficients per tensor index (padded blocks)
  double total_bits = 0.0;
};
// The RateReport bits of one tensor: tensor t (0..5) of grid, coded with step under the band
// models of tensor_index.
double EvaluateTensorBits(const VmGrid& grid, int t, float step, int tensor_index,
                          const encoder::RateConfig& config, const FactorizedEntropyModel& model);
RateReport EvaluateRate(const std::vector<const VmGrid*>& grids, const std::vector<float>& steps,
                        const encoder::RateConfig& config, const FactorizedEntropyModel& model);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_RATE_RATE_OBJECTIVE_H_
