// Factorized entropy model (Balle et al. 2018, "Variational image compression with a scale
// hyperprior", appendix 6.1), with the semantics of CompressAI's EntropyBottleneck:
// filters (3,3,3), i.e. a 1 -> 3 -> 3 -> 3 -> 1 monotone network c(x) = sigmoid(logits(x)) per
// model ("channel"). Each model is an independent density over x, the coefficient in units of
// its quantization step.
//
//   logits_cumulative(x): h = x; for layer i = 0..3:
//       h = softplus(matrix_i) @ h + bias_i;  if i < 3: h += tanh(factor_i) * tanh(h)
//   likelihood(x) = |sigmoid(s*u) - sigmoid(s*l)|, l = logits(x - 1/2), u = logits(x + 1/2),
//                   s = -sign(l + u)   (s = +1 when l + u == 0, where torch.sign gives 0 and
//                                       CompressAI would return likelihood 0: a measure-zero
//                                       deviation)
//   bits(x) = -log2(max(likelihood, likelihood_lower_bound)).
//
// Lower bound gradient (CompressAI LowerBound): the gradient reaches the likelihood where it is
// >= the bound, or where the incoming gradient is negative (descending would raise it). For a
// rate loss d bits / d likelihood < 0 always, so with pass_gradient_if_increasing (the default)
// tail samples keep pulling the model's tails out (and themselves in); without it, clamped
// samples get exactly zero gradient (x and parameters).
//
// Initialisation as CompressAI (init_scale 10): matrices constant log(expm1(1 / scale / f_out)),
// scale = init_scale^(1/4); biases U(-0.5, 0.5); factors 0.
//
// Parameter layout, 43 floats per model, models one after another in params():
//   [0,3) matrix0 (3x1)  [3,12) matrix1 (3x3, row k = output)  [12,21) matrix2 (3x3)
//   [21,24) matrix3 (1x3)  [24,27) bias0  [27,30) bias1  [30,33) bias2  [33] bias3
//   [34,37) factor0  [37,40) factor1  [40,43) factor2
// grads() has the same layout; train it with trainer/train/adam.h.
#ifndef ECRF_TRAINER_RATE_ENTROPY_MODEL_H_
#define ECRF_TRAINER_RATE_ENTROPY_MODEL_H_

#include <cstddef>
#include <cstdint>
#include <vector>

namespace ecrf {
namespace trainer {

inline constexpr int kEntropyParamsPerModel = 43;
inline constexpr int kEntropyMatrixOffset[4] = {0, 3, 12, 21};
inline constexpr int kEntropyBiasOffset[4] = {24, 27, 30, 33};
inline constexpr int kEntropyFactorOffset[3] = {34, 37, 40};

struct EntropyModelOptions {
  float init_scale = 10.f;
  float likelihood_lower_bound = 1e-9f;
  bool pass_gradient_if_increasing = true;  // CompressAI LowerBound; see above
};

// A run of values x[begin, end) that all use `model`.
struct EntropySegment {
  int model = 0;
  size_t begin = 0;
  size_t end = 0;
};

class FactorizedEntropyModel {
 public:
  FactorizedEntropyModel() = default;
  // num_models >= 1; deterministic for (seed).
  void Init(int num_models, uint64_t seed, const EntropyModelOptions& options = {});

  int num_models() const { return num_models_; }
  const EntropyModelOptions& options() const { return options_; }
  std::vector<float>& params() { return params_; }
  const std::vector<float>& params() const { return params_; }
  std::vector<float>& grads() { return grads_; }
  const std::vector<float>& grads() const { return grads_; }
  float* model_params(int model) { return params_.data() + model * kEntropyParamsPerModel; }
  const float* model_params(int model) const {
    return params_.data() + model * kEntropyParamsPerModel;
  }
  void ZeroGrads();

  // Fast float path (vectorised, OpenMP over chunks). Returns sum_i bits(x[i]) over all segments
  // (double accumulation). Optional outputs:
  //   bits[i] = bits(x[i]);   dbits_dx[i] = grad_scale * d bits(x[i]) / d x[i] (overwritten);
  //   accumulate_param_grads: grads() += grad_scale * d(sum bits) / d params.
  // Positions of x not covered by a segment are not touched. Not reentrant when accumulating.
  double Bits(const float* x, const EntropySegment* segments, int num_segments, float* bits,
              float* dbits_dx, float grad_scale, bool accumulate_param_grads);
  double Bits(int model, const float* x, size_t n, float* bits, float* dbits_dx, float grad_scale,
              bool accumulate_param_grads) {
    const EntropySegment s{model, 0, n};
    return Bits(x, &s, 1, bits, dbits_dx, grad_scale, accumulate_param_grads);
  }

  // Same computation in double for one value (tests, encoder CDF tables). dbits_dx and
  // dparams (43 values, accumulated +=) may be null.
  double BitsDouble(int model, double x, double* dbits_dx, double* dparams) const;
  // logits_cumulative(x) in double; the CDF is sigmoid of it.
  double LogitsCumulative(int model, double x) const;
  // likelihood(x) in double, lower bound applied.
  double Likelihood(int model, double x) const;

 private:
  int num_models_ = 0;
  EntropyModelOptions options_;
  std::vector<float> params_;
  std::vector<float> grads_;
};

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_RATE_ENTROPY_MODEL_H_
