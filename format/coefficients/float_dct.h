// Orthonormal DCT-II (forward) and DCT-III (inverse) over 1D-3D blocks, in floating point.
// The trainer and the encoder use it; the decoder uses the integer inverse in int_idct.h, which
// approximates InverseDct to within one unit of its output resolution.
//
// Forward: X[k] = a_k * sum_n x[n] cos(pi (2n+1) k / 2N), a_0 = sqrt(1/N), a_k = sqrt(2/N).
// Separable over the axes of an n0 x n1 x n2 block (n2 contiguous); axes of length 1 are identity.
// The transform is orthonormal, so InverseDct is also the gradient (adjoint) of ForwardDct.
#ifndef ECRF_FORMAT_COEFFICIENTS_FLOAT_DCT_H_
#define ECRF_FORMAT_COEFFICIENTS_FLOAT_DCT_H_

namespace ecrf {

// Row k of the N-point orthonormal DCT-II matrix, entry n: a_k cos(pi (2n+1) k / 2N).
// N must be a valid block length (1..32, power of two). Returns a table of N*N doubles.
const double* DctMatrix(int n);

// In place. data has dims[0]*dims[1]*dims[2] elements; dims must satisfy IsValidBlockShape.
void ForwardDct(double* data, const int dims[3]);
void InverseDct(double* data, const int dims[3]);
void ForwardDct(float* data, const int dims[3]);
void InverseDct(float* data, const int dims[3]);

}  // namespace ecrf

#endif  // ECRF_FORMAT_COEFFICIENTS_FLOAT_DCT_H_
