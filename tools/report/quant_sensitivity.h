// Where the quantization of a trained run costs PSNR: for each coded tensor, the rendering error
// that noise of its own quantization step adds on its coded (nonzero) coefficients, and what an
// allocation of the steps by equal slopes would gain at the same rate.
//
// Method: the decoded model (every tensor reconstructed from its quantized block-DCT
// coefficients, the head as coded) renders a fixed batch of training rays. For tensor t, uniform
// noise in [-step/2, step/2] on the coefficients whose level is nonzero (the quantization noise of
// a uniform quantizer, the error the coded levels carry) is added and subtracted (antithetic
// pair: the first-order term cancels, what remains is the curvature the noise pays), and the
// mean of the two MSE increases is the tensor's quantization cost D_t.
//
// Why per nonzero level: at the rates ecrf codes, most coefficients are zero and stay so whatever
// the step; the step sets the error and the bits of the nonzero ones (high-rate theory: D = a
// step^2, R = -n log2 step per nonzero level). At the rate-distortion optimum, dD/dR is equal for
// every tensor, i.e. D_t / n_t (the slope, up to a constant) is. Reallocating the steps to equal
// slopes at the same total rate scales the sum of the D_t by the n-weighted geometric mean of the
// slopes over their arithmetic mean: the predicted gain.
#ifndef ECRF_TOOLS_REPORT_QUANT_SENSITIVITY_H_
#define ECRF_TOOLS_REPORT_QUANT_SENSITIVITY_H_

#include <cstdint>
#include <string>
#include <vector>

#include "encoder/coded_tensors.h"
#include "encoder/scene_encoder.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {

// The model a file of these steps, blocks and head levels decodes to (mlp_max_level 0: the head
// as is): every tensor reconstructed from its quantized block-DCT coefficients.
trainer::TensorfModel DecodedModel(const trainer::TensorfModel& trained,
                                   const std::vector<float>& steps,
                                   const encoder::RateConfig& blocks, int mlp_max_level);

// A trained run as the report commands probe it: its model, the options that encode it (the
// run's own steps, blocks and head levels) and a batch of its training rays.
struct TrainedRun {
  trainer::CheckpointRunInfo info;
  trainer::TensorfModel model;
  encoder::EncodeOptions options;
  int rays = 0;
  std::vector<float> origins, dirs, rgb;  // rays x 3 each
};
// run: a run directory or its checkpoint.ckpt; the rays are drawn from the training views with
// `seed`. Throws when the checkpoint has no stored configuration.
TrainedRun LoadTrainedRun(const std::string& run, int rays, uint64_t seed);

struct TensorSensitivity {
  std::string name;
  float step = 0.f;
  long nonzero = 0;             // coefficients with a nonzero level
  double mean_abs_level = 0.0;  // over the nonzero ones
  double dmse = 0.0;            // D_t: MSE added by noise of the step on the nonzero levels
  double slope = 0.0;           // D_t / nonzero (0 without nonzero levels)
  float balanced_step = 0.f;    // the step of equal slopes at the same rate (high-rate model)
};

struct SensitivityReport {
  double mse = 0.0;                 // of the decoded model on the rays
  double quant_mse = 0.0;           // sum of the D_t
  double balanced_quant_mse = 0.0;  // the same after reallocating the steps (prediction)
  double predicted_gain_db = 0.0;   // PSNR gain of that reallocation (prediction)
  int rays = 0;
  std::vector<TensorSensitivity> tensors;  // the 12 coded tensors, in stream order
};

// `model` is the trained (float) model; steps (12), blocks and mlp_max_level (0: the head as
// is) describe its coding. Rays: n x 3 origins, directions, colours. noise_scale multiplies the
// noise (1: the step's own quantization noise). Deterministic for a seed.
SensitivityReport MeasureQuantSensitivity(const trainer::TensorfModel& model,
                                          const std::vector<float>& steps,
                                          const encoder::RateConfig& blocks, int mlp_max_level,
                                          int n, const float* origins, const float* dirs,
                                          const float* rgb, uint64_t seed,
                                          double noise_scale = 1.0);

int RunReportSensitivity(int argc, char** argv);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_REPORT_QUANT_SENSITIVITY_H_
