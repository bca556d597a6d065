// TensoRF's positional_encoding and a fast vectorizable sin/cos used by it.
//
// PE(x, F) for C channels: argument a[c*F + f] = x_c * 2^f (c-major), output
// [sin(a) (C*F values), cos(a) (C*F values)]. Nothing of x itself is included (TensoRF
// concatenates the raw inputs separately).
#ifndef ECRF_TRAINER_MODEL_POSITIONAL_ENCODING_H_
#define ECRF_TRAINER_MODEL_POSITIONAL_ENCODING_H_

namespace ecrf {
namespace trainer {

// s[i] = sin(x[i]), c[i] = cos(x[i]); absolute error <= ~1e-7 for |x| < 1e4 (Cody-Waite range
// reduction + minimax polynomials, branch-free so the compiler vectorizes it); larger |x| fall
// back to std::sin/std::cos. x, s and c may not overlap.
void FastSinCos(const float* x, int count, float* s, float* c);

// out must have 2 * channels * freqs floats. Odd frequencies come from the even one below by the
// double-angle formulas (absolute error <= ~4e-7), halving the sin/cos work.
void PositionalEncoding(const float* x, int channels, int freqs, float* out);

// PositionalEncoding of `rows` rows at once: row r reads x + r * x_stride (channels floats) and
// writes out + r * out_stride (2 * channels * freqs floats). tmp: 3 * rows * channels floats.
void PositionalEncodingRows(const float* x, int x_stride, int rows, int channels, int freqs,
                            float* out, int out_stride, float* tmp);

// Backward of PositionalEncoding: given the forward output pe (sin then cos, as written by
// PositionalEncoding) and dL/dpe, adds dL/dx into dx (channels floats).
void PositionalEncodingBackward(const float* pe, const float* dl_dpe, int channels, int freqs,
                                float* dx);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_MODEL_POSITIONAL_ENCODING_H_
