#include "trainer/model/positional_encoding.h"

#include <cmath>
#include <cstdint>
#include <vector>

#include "decoder/fast_sincos.h"

namespace ecrf {
namespace trainer {
namespace {

// Inputs above this use the library functions (without FMA the reduction loses accuracy beyond).
constexpr float kFastLimit = 1.0e4f;

void SinCosKernel(const float* __restrict x, int count, float* __restrict s, float* __restrict c) {
  using namespace fast_sincos;  // NOLINT(google-build-using-namespace)
  for (int i = 0; i < count; ++i) {
    const float v = x[i];
    const float k = Quadrant(v);
    const int32_t q = static_cast<int32_t>(k);
    const float r = Reduce(v, k);
    const float z = r * r;
    const float ps = SinPolynomial(r, z);
    const float pc = CosPolynomial(z);
    const bool swap = (q & 1) != 0;
    const float sv = swap ? pc : ps;
    const float cv = swap ? ps : pc;
    const float ssign = ((q & 2) != 0) ? -1.0f : 1.0f;
    const float csign = (((q + 1) & 2) != 0) ? -1.0f : 1.0f;
    s[i] = sv * ssign;
    c[i] = cv * csign;
  }
}

}  // namespace

void FastSinCos(const float* x, int count, float* s, float* c) {
  SinCosKernel(x, count, s, c);
  int slow = 0;  // integer OR-reduction so this check vectorizes too; NaN counts as slow
  for (int i = 0; i < count; ++i) slow |= (std::fabs(x[i]) < kFastLimit) ? 0 : 1;
  if (slow) {
    for (int i = 0; i < count; ++i) {
      if (!(std::fabs(x[i]) < kFastLimit)) {
        s[i] = std::sin(x[i]);
        c[i] = std::cos(x[i]);
      }
    }
  }
}

void PositionalEncodingRows(const float* x, int x_stride, int rows, int channels, int freqs,
                            float* out, int out_stride, float* tmp) {
  const int n = rows * channels;
  const int m = channels * freqs;
  float* __restrict a = tmp;
  float* __restrict s = tmp + n;
  float* __restrict c = tmp + 2 * n;
  for (int f = 0; f < freqs; f += 2) {
    const float scale = std::ldexp(1.0f, f);
    for (int r = 0; r < rows; ++r) {
      for (int ch = 0; ch < channels; ++ch) a[r * channels + ch] = x[r * x_stride + ch] * scale;
    }
    FastSinCos(a, n, s, c);
    const bool odd_too = f + 1 < freqs;
    for (int r = 0; r < rows; ++r) {
      float* __restrict o = out + static_cast<long>(r) * out_stride;
      const float* sr = s + r * channels;
      const float* cr = c + r * channels;
      for (int ch = 0; ch < channels; ++ch) {
        const float sv = sr[ch];
        const float cv = cr[ch];
        o[ch * freqs + f] = sv;
        o[m + ch * freqs + f] = cv;
        if (odd_too) {  // sin(2a) = 2 sin(a) cos(a), cos(2a) = (cos(a) - sin(a)) (cos(a) + sin(a))
          o[ch * freqs + f + 1] = 2.0f * sv * cv;
          o[m + ch * freqs + f + 1] = (cv - sv) * (cv + sv);
        }
      }
    }
  }
}

void PositionalEncoding(const float* x, int channels, int freqs, float* out) {
  std::vector<float> tmp(3 * static_cast<size_t>(channels));
  PositionalEncodingRows(x, channels, 1, channels, freqs, out, 2 * channels * freqs, tmp.data());
}

void PositionalEncodingBackward(const float* pe, const float* dl_dpe, int channels, int freqs,
                                float* dx) {
  const int m = channels * freqs;
  for (int ch = 0; ch < channels; ++ch) {
    float acc = 0.0f;
    float scale = 1.0f;
    for (int f = 0; f < freqs; ++f) {
      const int i = ch * freqs + f;
      // d sin(a)/da = cos(a), d cos(a)/da = -sin(a), da/dx = 2^f.
      acc += scale * (dl_dpe[i] * pe[m + i] - dl_dpe[m + i] * pe[i]);
      scale *= 2.0f;
    }
    dx[ch] += acc;
  }
}

}  // namespace trainer
}  // namespace ecrf
