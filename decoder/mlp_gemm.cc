#include "decoder/mlp_gemm.h"

#include <cstring>

namespace ecrf {
namespace dec {
namespace {

#if defined(__GNUC__)
#define ECRF_ALWAYS_INLINE inline __attribute__((always_inline))
typedef float V4 __attribute__((vector_size(16)));
#if defined(__AVX512F__)
typedef float VBuild __attribute__((vector_size(64)));
#elif defined(__AVX__)
typedef float VBuild __attribute__((vector_size(32)));
#else
typedef V4 VBuild;  // wider generic vectors are lowered through the stack on SSE / NEON / wasm
#endif

// Columns [j0, j0 + 2 * lanes of V) of 4 rows. Named accumulators (not arrays) so they stay in
// registers (plain loops over small accumulator arrays get scalarised by GCC's SLP pass). Every
// element sums over k in the same order whatever V is: the width never changes a result.
template <typename V>
ECRF_ALWAYS_INLINE void Block4(const float* x0, const float* x1, const float* x2, const float* x3,
                               int K, const float* wt, int ldw, const float* bias, int j0,
                               bool relu, float* y0, float* y1, float* y2, float* y3) {
  constexpr int kLanes = sizeof(V) / sizeof(float);
  V a0, b0, a1, b1, a2, b2, a3, b3;
  std::memcpy(&a0, bias + j0, sizeof(V));
  std::memcpy(&b0, bias + j0 + kLanes, sizeof(V));
  a1 = a2 = a3 = a0;
  b1 = b2 = b3 = b0;
  const float* w = wt + j0;
  for (int k = 0; k < K; ++k, w += ldw) {
    V wa, wb;
    std::memcpy(&wa, w, sizeof(V));
    std::memcpy(&wb, w + kLanes, sizeof(V));
    const float s0 = x0[k], s1 = x1[k], s2 = x2[k], s3 = x3[k];
    a0 += s0 * wa;
    b0 += s0 * wb;
    a1 += s1 * wa;
    b1 += s1 * wb;
    a2 += s2 * wa;
    b2 += s2 * wb;
    a3 += s3 * wa;
    b3 += s3 * wb;
  }
  if (relu) {
    const V z = {};  // zeros of any width (a0 - a0 would be NaN where a0 is infinite)
    a0 = a0 > z ? a0 : z;
    b0 = b0 > z ? b0 : z;
    a1 = a1 > z ? a1 : z;
    b1 = b1 > z ? b1 : z;
    a2 = a2 > z ? a2 : z;
    b2 = b2 > z ? b2 : z;
    a3 = a3 > z ? a3 : z;
    b3 = b3 > z ? b3 : z;
  }
  std::memcpy(y0 + j0, &a0, sizeof(V));
  std::memcpy(y0 + j0 + kLanes, &b0, sizeof(V));
  std::memcpy(y1 + j0, &a1, sizeof(V));
  std::memcpy(y1 + j0 + kLanes, &b1, sizeof(V));
  std::memcpy(y2 + j0, &a2, sizeof(V));
  std::memcpy(y2 + j0 + kLanes, &b2, sizeof(V));
  std::memcpy(y3 + j0, &a3, sizeof(V));
  std::memcpy(y3 + j0 + kLanes, &b3, sizeof(V));
}

// Wide blocks of V while they fit, then blocks of 8 columns.
template <typename V>
ECRF_ALWAYS_INLINE void Gemm4Of(const float* x0, const float* x1, const float* x2, const float* x3,
                                int K, const float* wt, int ldw, const float* bias, int ncols,
                                bool relu, float* y0, float* y1, float* y2, float* y3) {
  constexpr int kWide = 2 * static_cast<int>(sizeof(V) / sizeof(float));
  int j0 = 0;
  for (; j0 + kWide <= ncols; j0 += kWide)
    Block4<V>(x0, x1, x2, x3, K, wt, ldw, bias, j0, relu, y0, y1, y2, y3);
  for (; j0 < ncols; j0 += 8)
    Block4<V4>(x0, x1, x2, x3, K, wt, ldw, bias, j0, relu, y0, y1, y2, y3);
}

void Gemm4Portable(const float* x0, const float* x1, const float* x2, const float* x3, int K,
                   const float* wt, int ldw, const float* bias, int ncols, bool relu, float* y0,
                   float* y1, float* y2, float* y3) {
  Gemm4Of<VBuild>(x0, x1, x2, x3, K, wt, ldw, bias, ncols, relu, y0, y1, y2, y3);
}

// x86-64: the same template compiled for wider vectors. The target attributes name AVX2 and
// AVX-512F only, never FMA, so a * b + c stays two roundings as in the portable kernel.
#if defined(__x86_64__)
#define ECRF_GEMM_X86_KERNELS 1
typedef float V8 __attribute__((vector_size(32)));
typedef float V16 __attribute__((vector_size(64)));

__attribute__((target("avx2"))) void Gemm4Avx2(const float* x0, const float* x1, const float* x2,
                                               const float* x3, int K, const float* wt, int ldw,
                                               const float* bias, int ncols, bool relu, float* y0,
                                               float* y1, float* y2, float* y3) {
  Gemm4Of<V8>(x0, x1, x2, x3, K, wt, ldw, bias, ncols, relu, y0, y1, y2, y3);
}

__attribute__((target("avx512f"))) void Gemm4Avx512(const float* x0, const float* x1,
                                                    const float* x2, const float* x3, int K,
                                                    const float* wt, int ldw, const float* bias,
                                                    int ncols, bool relu, float* y0, float* y1,
                                                    float* y2, float* y3) {
  Gemm4Of<V16>(x0, x1, x2, x3, K, wt, ldw, bias, ncols, relu, y0, y1, y2, y3);
}
#endif

#else  // not GCC or Clang: scalar loops in the same order
void Gemm4Portable(const float* x0, const float* x1, const float* x2, const float* x3, int K,
                   const float* wt, int ldw, const float* bias, int ncols, bool relu, float* y0,
                   float* y1, float* y2, float* y3) {
  float* y[4] = {y0, y1, y2, y3};
  const float* x[4] = {x0, x1, x2, x3};
  for (int r = 0; r < 4; ++r) {
    for (int j = 0; j < ncols; ++j) y[r][j] = bias[j];
    for (int k = 0; k < K; ++k) {
      const float s = x[r][k];
      const float* w = wt + static_cast<long>(k) * ldw;
      for (int j = 0; j < ncols; ++j) y[r][j] += s * w[j];
    }
    if (relu) {
      for (int j = 0; j < ncols; ++j) y[r][j] = y[r][j] > 0.f ? y[r][j] : 0.f;
    }
  }
}
#endif

}  // namespace

bool GemmKernelAvailable(GemmKernel kernel) {
  switch (kernel) {
    case GemmKernel::kPortable:
      return true;
#if defined(ECRF_GEMM_X86_KERNELS)
    case GemmKernel::kAvx2:
      // GCC's and Clang's checks include the OS's support for the wide registers (XGETBV).
      return __builtin_cpu_supports("avx2");
    case GemmKernel::kAvx512:
      return __builtin_cpu_supports("avx512f");
#endif
    default:
      return false;
  }
}

GemmKernel BestGemmKernel() {
  if (GemmKernelAvailable(GemmKernel::kAvx512)) return GemmKernel::kAvx512;
  if (GemmKernelAvailable(GemmKernel::kAvx2)) return GemmKernel::kAvx2;
  return GemmKernel::kPortable;
}

const char* GemmKernelName(GemmKernel kernel) {
  switch (kernel) {
    case GemmKernel::kAvx2:
      return "avx2";
    case GemmKernel::kAvx512:
      return "avx512";
    default:
      return "portable";
  }
}

Gemm4Fn Gemm4For(GemmKernel kernel) {
  if (!GemmKernelAvailable(kernel)) return Gemm4Portable;
#if defined(ECRF_GEMM_X86_KERNELS)
  if (kernel == GemmKernel::kAvx512) return Gemm4Avx512;
  if (kernel == GemmKernel::kAvx2) return Gemm4Avx2;
#endif
  return Gemm4Portable;
}

}  // namespace dec
}  // namespace ecrf
