#include "trainer/rate/train_rate_control.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ecrf {
namespace trainer {

float InitialLambdaForSize(size_t target_bytes, size_t float32_bytes) {
  if (target_bytes == 0 || float32_bytes == 0)
    throw std::invalid_argument("InitialLambdaForSize: zero size");
  const double share = double(target_bytes) / double(float32_bytes);
  const double lambda = 1e-10 * std::pow(share / 0.0225, -1.0 / 0.45);
  return float(std::clamp(lambda, 1e-12, 1e-8));
}

LambdaController::LambdaController(size_t target_bytes, float lambda_e, size_t last_bytes)
    : target_(target_bytes), lambda_(lambda_e), last_bytes_(last_bytes) {
  if (target_bytes == 0) throw std::invalid_argument("LambdaController: target of 0 bytes");
  if (!(lambda_e > 0.f)) throw std::invalid_argument("LambdaController: lambda_e must be > 0");
}

float LambdaController::Update(size_t file_bytes) {
  const size_t bytes = std::max<size_t>(file_bytes, 1);
  double log_error = std::log(double(bytes) / double(target_));
  if (last_bytes_ > 0) log_error += kTrendHorizon * std::log(double(bytes) / double(last_bytes_));
  last_bytes_ = bytes;
  const double factor = std::clamp(std::exp(kGain * log_error), 1.0 / 3.0, 3.0);
  lambda_ = float(std::clamp(double(lambda_) * factor, 1e-14, 1e-6));
  return lambda_;
}

}  // namespace trainer
}  // namespace ecrf
