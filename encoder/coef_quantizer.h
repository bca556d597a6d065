// The encoder's scalar quantizer of grid DCT coefficients, shared by the encoder and by
// quantization-aware training so that training sees exactly the levels the file will carry.
//
// level = sign(c) * floor(|c| / step + offset). offset 0.5 is rounding to nearest (half away from
// zero); a smaller offset widens the dead zone around zero and pulls every level toward it, as
// video encoders do (HEVC's reference encoder: 1/3 intra, 1/6 inter): the levels it drops or
// shrinks cost more bits than their share of the distortion. The decoder is unchanged
// (reconstruction is level * step either way).
#ifndef ECRF_ENCODER_COEF_QUANTIZER_H_
#define ECRF_ENCODER_COEF_QUANTIZER_H_

#include <cmath>

namespace ecrf {
namespace encoder {

inline constexpr float kRoundToNearest = 0.5f;

// std::round exactly (floor(x + 0.5) differs for the double just below 0.5), written with trunc,
// which compilers inline and vectorize, where std::round is a library call: q - trunc(q) is
// exact, and NaN and infinities pass through.
inline double RoundHalfAwayFromZero(double q) {
  const double whole = std::trunc(q);
  return std::fabs(q - whole) >= 0.5 ? whole + std::copysign(1.0, q) : whole;
}

inline double QuantizeLevel(double coefficient, double step, double offset) {
  if (offset == 0.5) return RoundHalfAwayFromZero(coefficient / step);
  const double magnitude = std::floor(std::fabs(coefficient) / step + offset);
  return coefficient < 0.0 ? -magnitude : magnitude;
}

}  // namespace encoder
}  // namespace ecrf

#endif  // ECRF_ENCODER_COEF_QUANTIZER_H_
