// The row-blocked matrix products of the appearance MLP (decoder/mlp.h), with one kernel per
// instruction set chosen at run time.
//
// Every kernel computes each output element as bias + x[0] * w[0] + x[1] * w[1] + ... in
// increasing k, one rounded multiply and one rounded add per term (no fused multiply-add: the
// decoder builds with -ffp-contract=off and no kernel enables FMA). Only the number of columns
// computed side by side differs (4 on SSE2 / NEON / wasm-simd128, 8 with AVX2, 16 with AVX-512F),
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

// y_r[j] = bias[j] + sum_{k < K} x_r[k] * wt[k * ldw + j] for the 4 rows r and j < ncols (a
// multiple of 8), then max(0, .) when relu.
using Gemm4Fn = void (*)(const float* x0, const float* x1, const float* x2, const float* x3, int K,
                         const float* wt, int ldw, const float* bias, int ncols, bool relu,
                         float* y0, float* y1, float* y2, float* y3);

// Whether this build has the kernel and this CPU (and OS) can run it; kPortable always.
bool GemmKernelAvailable(GemmKernel kernel);
// The widest available kernel.
GemmKernel BestGemmKernel();
const char* GemmKernelName(GemmKernel kernel);
// The kernel's function; an unavailable kernel gives the portable one.
Gemm4Fn Gemm4For(GemmKernel kernel);

}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_DECODER_MLP_GEMM_H_
