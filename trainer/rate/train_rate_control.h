// Rate control during training: lambda_e adapted so that the file lands at a size.
//
// The rate phase encodes the model every few iterations (the real encoder: its context-modelled
// coefficient coder codes 25-35% below the factorized model's estimate, so the estimate is no
// measure of the file) and moves lambda_e in log space toward the size, a multiplicative
// Lagrange-multiplier update on the size the file is heading for:
//   log lambda += gain * (log(bytes / target) + horizon * log(bytes / previous bytes)),
// each update capped to a factor of 3. The file's bytes respond to lambda_e with a delay (the
// grids shrink over a few hundred steps), so the gain stays below the full correction (bytes ~
// lambda^-0.45 measured on chair would need 2.2), and the trend term stops lambda_e rising while
// the file is already falling toward the target: without it, chair-800 trained 24,000 steps
// before its rate phase came in at 2.5x its 500 KB target, lambda_e rose 44x before the file
// answered, and the file fell to 290 KB, from which coefficients pushed into the quantizer's
// dead zone late in a run (low learning rates) regrow at 1-2 % per 100 steps. With a horizon of
// 3 updates a fit of that run's response (fast shrinking, slow regrowth, momentum) stays above
// 93 % of the target, and a response without the asymmetry settles about as fast as before.
// Encode-time rate control (encoder/encode_rate_control.h) finishes the last percent.
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
  // last_bytes: the file the previous update measured (0: none yet, as at the rate phase's start;
  // a resumed run passes its checkpoint's, so that it continues exactly).
  LambdaController(size_t target_bytes, float lambda_e, size_t last_bytes = 0);
  // The file encoded now has file_bytes; returns the lambda_e to train with from here on.
  float Update(size_t file_bytes);
  float lambda_e() const { return lambda_; }
  size_t target_bytes() const { return target_; }
  size_t last_bytes() const { return last_bytes_; }

  static constexpr double kGain = 1.2;
  static constexpr double kTrendHorizon = 3.0;  // updates ahead the trend is extrapolated

 private:
  size_t target_;
  float lambda_;
  size_t last_bytes_;
};

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_RATE_TRAIN_RATE_CONTROL_H_
