// Single-threaded float GEMM tuned for the appearance MLP's chunk shapes (a few hundred rows, at
// most a few hundred columns), where Eigen's general-purpose blocking leaves half the FMA
// throughput unused. Results are deterministic: the summation order depends only on the shape.
#ifndef ECRF_TRAINER_MODEL_SMALL_GEMM_H_
#define ECRF_TRAINER_MODEL_SMALL_GEMM_H_

#include <cstddef>

namespace ecrf {
namespace trainer {

// C(i,j) = (accumulate ? C(i,j) : 0) + sum_{p<K} A(i,p) * B(p,j)   for i < M, j < N.
// A(i,p) = a[i*a_row + p*a_col] (so a_col = 1 is a row-major A, a_row = 1 a transposed one);
// B(p,j) = b[p*ldb + j] (rows of B contiguous); C(i,j) = c[i*ldc + j].
// When accumulate is false C is only written, never read (it may hold NaN/garbage before).
// Single-threaded; no allocation; M, N, K >= 0 (any zero -> nothing, but with accumulate=false
// and K==0 C is set to 0). Never touches B or C beyond column N-1 or C beyond row M-1.
void SmallGemm(int M, int N, int K, const float* a, std::ptrdiff_t a_row, std::ptrdiff_t a_col,
               const float* b, std::ptrdiff_t ldb, float* c, std::ptrdiff_t ldc, bool accumulate);

// Which kernel was compiled in: "avx512", "avx2" or "portable".
const char* SmallGemmIsa();

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_MODEL_SMALL_GEMM_H_
