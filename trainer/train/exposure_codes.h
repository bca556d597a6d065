// Per-image exposure codes: the part of NeRF-W's per-image appearance that auto exposure and white
// balance need. Training frame v is modelled as gain_v[c] * C[c], C the radiance field's pixel
// (background included) and gain_v = exp(log_gain_v[c]) per channel. The codes are learnt with the
// field and left out of the file: a decoder renders the neutral exposure, which is pinned to the
// geometric mean of the training frames' gains (each channel's mean log gain is held at 0 after
// every step), so the field cannot drift in brightness against them.
//
// Why: a capture whose frames differ in exposure (phones, auto white balance) otherwise teaches
// the field view-dependent colour and haze that explain the frames' brightness, and those do not
// carry over to views it was not trained on.
#ifndef ECRF_TRAINER_TRAIN_EXPOSURE_CODES_H_
#define ECRF_TRAINER_TRAIN_EXPOSURE_CODES_H_

#include <cstdint>
#include <vector>

#include "trainer/train/adam.h"

namespace ecrf {
namespace trainer {

class ExposureCodes {
 public:
  // `views` codes, all gains 1 (views = 0: off).
  void Reset(int views);
  bool enabled() const { return !log_gain_.empty(); }
  int views() const { return static_cast<int>(log_gain_.size() / 3); }

  // The gains (n x 3) of n rays from these views.
  void Gains(int n, const uint32_t* view, float* gains) const;
  // One Adam step at `learning_rate` from the rays' gradients dL/dgain (n x 3, the gains Gains
  // gave), then each channel's mean log gain back to 0.
  void Step(int n, const uint32_t* view, const float* gains, const float* dl_dgain,
            float learning_rate);

  // The log gains, views x 3 (for checkpoints and reports).
  std::vector<float>& log_gain() { return log_gain_; }
  const std::vector<float>& log_gain() const { return log_gain_; }
  Adam& adam() { return adam_; }
  const Adam& adam() const { return adam_; }

 private:
  std::vector<float> log_gain_, grad_;
  Adam adam_;
};

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_EXPOSURE_CODES_H_
