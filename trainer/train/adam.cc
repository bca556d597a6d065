#include "trainer/train/adam.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace ecrf {
namespace trainer {

Adam::Adam(size_t size, const AdamConfig& config) : config_(config) { Reset(size); }

void Adam::Reset(size_t size) {
  m_.assign(size, 0.0f);
  v_.assign(size, 0.0f);
  step_ = 0;
}

void Adam::Keep(const std::vector<size_t>& indices) {
  std::vector<float> m(indices.size()), v(indices.size());
  for (size_t i = 0; i < indices.size(); ++i) {
    if (indices[i] >= m_.size()) throw std::out_of_range("Adam::Keep: index past the moments");
    m[i] = m_[indices[i]];
    v[i] = v_[indices[i]];
  }
  m_ = std::move(m);
  v_ = std::move(v);
}

void Adam::Step(float* params, const float* grads, size_t size, float learning_rate) {
  if (size != m_.size()) throw std::invalid_argument("Adam::Step: size differs from Reset");
  ++step_;
  // As torch.optim.Adam (single-tensor path): the bias corrections are Python floats (double).
  const double t = static_cast<double>(step_);
  const double bias_correction1 = 1.0 - std::pow(static_cast<double>(config_.beta1), t);
  const double bias_correction2 = 1.0 - std::pow(static_cast<double>(config_.beta2), t);
  const float neg_step_size = static_cast<float>(-learning_rate / bias_correction1);
  const float bias_correction2_sqrt = static_cast<float>(std::sqrt(bias_correction2));
  const float one_minus_beta1 = static_cast<float>(1.0 - static_cast<double>(config_.beta1));
  const float beta2 = config_.beta2;
  const float one_minus_beta2 = static_cast<float>(1.0 - static_cast<double>(config_.beta2));
  const float eps = config_.epsilon;
  constexpr long kBlock = 1 << 14;
  const long blocks = static_cast<long>((size + kBlock - 1) / kBlock);
  float* m_all = m_.data();
  float* v_all = v_.data();
  // A plain loop, not Eigen arrays: Eigen peels unaligned elements into scalar code that the
  // compiler contracts into FMAs while its packet code stays mul + add, so an element's update
  // depended on the buffer's address (and two runs of one seed drifted apart).
#pragma omp parallel for schedule(static) if (blocks > 4)
  for (long b = 0; b < blocks; ++b) {
    const size_t begin = static_cast<size_t>(b) * kBlock;
    const size_t end = std::min<size_t>(begin + kBlock, size);
    float* __restrict p = params;
    const float* __restrict g = grads;
    float* __restrict m = m_all;
    float* __restrict v = v_all;
#pragma omp simd
    for (size_t i = begin; i < end; ++i) {
      m[i] += one_minus_beta1 * (g[i] - m[i]);  // exp_avg.lerp_(grad, 1 - beta1)
      v[i] =
          v[i] * beta2 + (one_minus_beta2 * g[i]) * g[i];  // mul_(beta2).addcmul_(g, g, 1 - beta2)
      p[i] += neg_step_size * (m[i] / (std::sqrt(v[i]) / bias_correction2_sqrt + eps));  // addcdiv_
    }
  }
}

}  // namespace trainer
}  // namespace ecrf
