// The row-blocked matrix products of the appearance MLP (decoder/mlp.h), with one kernel per
// instruction set chosen at run time.
//
// Every kernel computes each output element as bias + x[0] * w[0] + x[1] * w[1] + ... in
// increasing k, one rounded multiply and one rounded add per term (no fused multiply-add: the
// decoder builds with -ffp-contract=off and no kernel enables FMA). Only the number of columns
// computed side by side differs (4 on SSE2 / NEON / wasm-simd128, 8 with AVX2, 32 with AVX-512F),
// so every kernel writes bit-identical results and SPEC.md 7.6's reference arithmetic holds on all
// of them (tests/decoder/mlp_test.cc checks this on every kernel the machine runs).
#ifndef ECRF_DECODER_MLP_GEMM_H_
#define ECRF_DECODER_MLP_GEMM_H_

namespace ecrf {
namespace dec {

enum class GemmKernel : int {
  kPortable = 0,  // generic vectors of the build's own target (SSE2 in a default x86-64 build)
  kAvx2 = 1,      // x86-64 with AVX2, 8 columns per vector
  kAvx512 = 2,    // x86-64 with AVX-512F, 16 columns per vector
};

// y[r][j] = bias[j] + sum_{i < nk} x[r][k_i] * wt[k_i * ldw + j] with k_i = ks[i], for the 8 rows
// r and j < ncols (a multiple of 8), then max(0, .) when relu. ks lists the terms in increasing k:
// nullptr for all of [0, nk) (a dense product), else only the k where some x[r][k] is not zero
// (NonZeroColumns8). A term left out adds x * w = +-0 (the weights are finite), which leaves
// every sum's value unchanged (at most a zero sum's sign, which neither the ReLU nor the sigmoid
// after it tells apart), so both give the same results (SPEC.md 7.6 sums over every k).
using Gemm8Fn = void (*)(const float* const* x, const int* ks, int nk, const float* wt, int ldw,
                         const float* bias, int ncols, bool relu, float* const* y);

// The k < K where one of x[0..7][k] is not zero (NaN counts as not zero), in increasing order,
// into ks; returns their count.
int NonZeroColumns8(const float* const* x, int K, int* ks);

// Whether this build has the kernel and this CPU (and OS) can run it; kPortable always.
bool GemmKernelAvailable(GemmKernel kernel);
// The widest available kernel.
GemmKernel BestGemmKernel();
const char* GemmKernelName(GemmKernel kernel);
// The kernel's function; an unavailable kernel gives the portable one.
Gemm8Fn Gemm8For(GemmKernel kernel);

}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_DECODER_MLP_GEMM_H_
