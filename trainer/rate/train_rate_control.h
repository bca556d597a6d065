// Rate control during training: lambda_e adapted so that the file lands at a size.
//
// The rate phase encodes the model every few iterations (the real encoder: its context-modelled
// coefficient coder codes 25-35% below the factorized model's estimate, so the estimate is no
// measure of the file) and moves lambda_e in log space toward the size, a multiplicative
// Lagrange-multiplier update: log lambda += gain * log(bytes / target), each update capped to a
// factor of 3. The file's bytes respond to lambda_e with a delay (the grids shrink over a few
// hundred steps), so the gain stays below the full correction (bytes ~ lambda^-0.45 measured on
// chair would need 2.2). Encode-time rate control (encoder/encode_rate_control.h) finishes the
// last percent.
#ifndef ECRF_TRAINER_RATE_TRAIN_RATE_CONTROL_H_
#define ECRF_TRAINER_RATE_TRAIN_RATE_CONTROL_H_

#include <cstddef>

namespace ecrf {
namespace trainer {

// A starting lambda_e for a file of target_bytes from a model of float32_bytes: the chair-400
// `fast` sweep (docs/reports/chair) fitted as bytes / float32 = 0.0225 * (lambda / 1e-10)^-0.45,
// clamped to [1e-12, 1e-8]. Other scenes differ by a factor the controller absorbs.
float InitialLambdaForSize(size_t target_bytes, size_t float32_bytes);

class LambdaController {
 public:
  LambdaController(size_t target_bytes, float lambda_e, float gain = 1.2f);
  // The file encoded now has file_bytes; returns the lambda_e to train with from here on.
  float Update(size_t file_bytes);
  float lambda_e() const { return lambda_; }
  size_t target_bytes() const { return target_; }

 private:
  size_t target_;
  float lambda_;
  float gain_;
};

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_RATE_TRAIN_RATE_CONTROL_H_
