// The density activation (SPEC.md 7.3): PyTorch's softplus with threshold 20. Header-only and
// shared by the decoder and the trainer.
#ifndef ECRF_DECODER_SOFTPLUS_H_
#define ECRF_DECODER_SOFTPLUS_H_

#include <cmath>

namespace ecrf {

inline float Softplus(float x) { return x > 20.f ? x : std::log1p(std::exp(x)); }

}  // namespace ecrf

#endif  // ECRF_DECODER_SOFTPLUS_H_
