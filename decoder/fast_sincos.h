// The arithmetic of the fast sin/cos that the appearance MLP's positional encoding uses, shared
// by the decoder (dec::FastSinCos, decoder/mlp.cc) and the trainer (trainer/model/
// positional_encoding.cc): Cody-Waite reduction by pi/2 and Cephes' minimax polynomials on
// [-pi/4, pi/4]; absolute error below 5e-7 for |x| <= 8192, the bound SPEC.md 7 sets for any
// conforming renderer's sin and cos. Each caller keeps its own quadrant selection (the decoder's
// is branch-free for its vector loop; the trainer's picks by integer quadrant) and its own
// fallback to std::sin/std::cos for large arguments.
#ifndef ECRF_DECODER_FAST_SINCOS_H_
#define ECRF_DECODER_FAST_SINCOS_H_

namespace ecrf {
namespace fast_sincos {

inline constexpr float kTwoOverPi = 0.636619772367581343f;
// pi/2 in three parts (Cephes' pi/4 split times 2): k * kHalfPi1 is exact for |k| < 2^16.
inline constexpr float kHalfPi1 = 1.5703125f;
inline constexpr float kHalfPi2 = 4.837512969970703125e-4f;
inline constexpr float kHalfPi3 = 7.54978995489188216e-8f;
// 1.5 * 2^23: adding and subtracting it rounds a float to the nearest integer.
inline constexpr float kRoundingMagic = 12582912.f;

// The nearest integer to v * 2/pi, as a float: the quadrant of v before reduction.
inline float Quadrant(float v) { return (v * kTwoOverPi + kRoundingMagic) - kRoundingMagic; }

// v - k pi/2, in [-pi/4, pi/4] for k = Quadrant(v).
inline float Reduce(float v, float k) {
  float r = v - k * kHalfPi1;
  r -= k * kHalfPi2;
  r -= k * kHalfPi3;
  return r;
}

// sin r and cos r on [-pi/4, pi/4], given r and r2 = r * r.
inline float SinPolynomial(float r, float r2) {
  return r + r * r2 * (-1.6666654611e-1f + r2 * (8.3321608736e-3f + r2 * -1.9515295891e-4f));
}
inline float CosPolynomial(float r2) {
  return 1.f - 0.5f * r2 +
         r2 * r2 *
             (4.166664568298827e-2f + r2 * (-1.388731625493765e-3f + r2 * 2.443315711809948e-5f));
}

}  // namespace fast_sincos
}  // namespace ecrf

#endif  // ECRF_DECODER_FAST_SINCOS_H_
