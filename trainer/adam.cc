#include "trainer/adam.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ecrf {
namespace trainer {

Adam::Adam(size_t size, const AdamConfig& config) : config_(config) { Reset(size); }

void Adam::Reset(size_t size) {
  m_.assign(size, 0.0f);
  v_.assign(size, 0.0f);
  step_ = 0;
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
#pragma omp parallel for schedule(static) if (blocks > 4)
  for (long b = 0; b < blocks; ++b) {
    const size_t begin = static_cast<size_t>(b) * kBlock;
    const Eigen::Index len = static_cast<Eigen::Index>(std::min<size_t>(kBlock, size - begin));
    Eigen::Map<Eigen::ArrayXf> p(params + begin, len);
    Eigen::Map<const Eigen::ArrayXf> g(grads + begin, len);
    Eigen::Map<Eigen::ArrayXf> m(m_all + begin, len);
    Eigen::Map<Eigen::ArrayXf> v(v_all + begin, len);
    m += one_minus_beta1 * (g - m);                   // exp_avg.lerp_(grad, 1 - beta1)
    v = v * beta2 + (one_minus_beta2 * g) * g;        // mul_(beta2).addcmul_(g, g, 1 - beta2)
    p += neg_step_size * (m / (v.sqrt() / bias_correction2_sqrt + eps));  // addcdiv_
  }
}

}  // namespace trainer
}  // namespace ecrf
