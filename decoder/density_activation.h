// The density activation (SPEC.md 7.4): sigma from the density feature plus HEAD density_shift,
// by HEAD density_activation: PyTorch's softplus with threshold 20, or ReLU. Header-only and
// shared by the decoder and the trainer.
#ifndef ECRF_DECODER_DENSITY_ACTIVATION_H_
#define ECRF_DECODER_DENSITY_ACTIVATION_H_

#include <cmath>

#include "format/scene_header.h"

namespace ecrf {

inline float Softplus(float x) { return x > 20.f ? x : std::log1p(std::exp(x)); }

// sigma of a shifted density feature x.
inline float ActivateDensity(DensityActivation a, float x) {
  if (a == DensityActivation::kRelu) return x > 0.f ? x : 0.f;
  return Softplus(x);
}

}  // namespace ecrf

#endif  // ECRF_DECODER_DENSITY_ACTIVATION_H_
