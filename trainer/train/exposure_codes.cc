#include "trainer/train/exposure_codes.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ecrf {
namespace trainer {

void ExposureCodes::Reset(int views) {
  if (views < 0) throw std::invalid_argument("ExposureCodes: negative view count");
  log_gain_.assign(static_cast<size_t>(views) * 3, 0.f);
  grad_.assign(log_gain_.size(), 0.f);
  adam_ = Adam(log_gain_.size(), AdamConfig());
}

void ExposureCodes::Gains(int n, const uint32_t* view, float* gains) const {
  // One exp per view and channel, not per ray.
  std::vector<float> per_view(log_gain_.size());
  for (size_t k = 0; k < per_view.size(); ++k) per_view[k] = std::exp(log_gain_[k]);
  for (int i = 0; i < n; ++i) {
    if (view[i] >= static_cast<uint32_t>(views()))
      throw std::out_of_range("ExposureCodes::Gains: view index past the codes");
    for (int c = 0; c < 3; ++c) gains[3 * i + c] = per_view[3 * size_t(view[i]) + c];
  }
}

void ExposureCodes::Step(int n, const uint32_t* view, const float* gains, const float* dl_dgain,
                         float learning_rate) {
  if (!enabled()) return;
  std::fill(grad_.begin(), grad_.end(), 0.f);
  // d gain / d log_gain = gain. Summed in ray order: the same for every thread count.
  for (int i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c)
      grad_[3 * size_t(view[i]) + c] += dl_dgain[3 * i + c] * gains[3 * i + c];
  }
  adam_.Step(log_gain_.data(), grad_.data(), log_gain_.size(), learning_rate);
  const int v = views();
  for (int c = 0; c < 3; ++c) {
    double mean = 0.0;
    for (int k = 0; k < v; ++k) mean += log_gain_[3 * size_t(k) + c];
    mean /= v;
    for (int k = 0; k < v; ++k) log_gain_[3 * size_t(k) + c] -= static_cast<float>(mean);
  }
}

}  // namespace trainer
}  // namespace ecrf
