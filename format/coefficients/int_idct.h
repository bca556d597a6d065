// The normative integer inverse DCT (SPEC.md "Integer inverse DCT").
//
// Input: quantized coefficients q (int32, |q| <= 127 for 8-bit tensors, <= 32767 for 16-bit) of
// one n0 x n1 x n2 block. Output: int32 samples in units of 2^-P quantization steps, where
// P = IdctOutputFracBits(coef_bits) (8 for 8-bit, 4 for 16-bit coefficients), i.e. the decoded
// grid value is out * step / 2^P.
//
// Separable passes along axis 2, then 1, then 0 (axes of length 1 are skipped). Each pass
// multiplies by an integer DCT-III matrix scaled by 2^26, accumulates in int64, adds half of the
// divisor, shifts right arithmetically and clips to int32. Intermediates keep P + 6 fractional
// bits (6 guard bits), so the result stays within one output unit of the float64 orthonormal
// inverse DCT. Every step is exact integer arithmetic: all platforms produce the same bits.
#ifndef ECRF_FORMAT_COEFFICIENTS_INT_IDCT_H_
#define ECRF_FORMAT_COEFFICIENTS_INT_IDCT_H_

#include <cstdint>

namespace ecrf {

constexpr int kIdctMatrixBits = 26;
constexpr int kIdctGuardBits = 6;

// P: fractional bits of the output, per coefficient bit depth (8 or 16). -1 for other depths.
int IdctOutputFracBits(int coef_bits);

// K_N[j] = round(2^26 * sqrt(2/N) * cos(pi j / 2N)) for j = 0..N (the table printed in SPEC.md);
// N in {2, 4, 8, 16, 32}. Returns null for other N.
const int32_t* IdctCosineTable(int n);

// Entry (k, i) of the integer N-point inverse matrix: the weight of coefficient k in sample i.
int32_t IdctMatrixEntry(int n, int k, int i);

// coeffs and out have dims[0]*dims[1]*dims[2] elements (they may not overlap). dims must be a
// legal block shape (IsValidBlockShape) and coef_bits 8 or 16; the caller validates both.
// Work is proportional to the bounding box of the nonzero coefficients: all-zero blocks and
// low-frequency blocks are cheap, and the result is the same as the full computation.
void InverseDctInt(const int32_t* coeffs, const int dims[3], int coef_bits, int32_t* out);

}  // namespace ecrf

#endif  // ECRF_FORMAT_COEFFICIENTS_INT_IDCT_H_
