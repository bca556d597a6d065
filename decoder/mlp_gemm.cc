#include "decoder/mlp_gemm.h"

#include <cstdint>
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

// Columns [j0, j0 + kVecs * lanes of V) of kRows (4 or 8) rows. Named accumulators (not arrays)
// so they stay in registers (plain loops over small accumulator arrays get scalarised by GCC's SLP
// pass). With AVX2 and AVX-512, eight rows share each load of the weights, which is what bounds a
// narrower block there (the weight matrices live in L2, not L1); with 4-lane vectors the
// broadcasts of x cost more than the loads, so 4 rows of two vectors do better. Every element
// sums over k in the same order whatever V, kVecs and kRows are: the shape never changes a result.
template <typename V, int kVecs, int kRows, bool kDense>
ECRF_ALWAYS_INLINE void Block(const float* const* x, const int* ks, int nk, const float* wt,
                              int ldw, const float* bias, int j0, bool relu, float* const* y) {
  static_assert(kVecs == 1 || kVecs == 2, "one or two vectors of columns");
  static_assert(kRows == 4 || kRows == 8, "4 or 8 rows");
  constexpr int kLanes = sizeof(V) / sizeof(float);
  const float *x0 = x[0], *x1 = x[1], *x2 = x[2], *x3 = x[3];
  const float* x4 = kRows == 8 ? x[4] : x[0];
  const float* x5 = kRows == 8 ? x[5] : x[0];
  const float* x6 = kRows == 8 ? x[6] : x[0];
  const float* x7 = kRows == 8 ? x[7] : x[0];
  V a0, a1, a2, a3, a4, a5, a6, a7, b0, b1, b2, b3, b4, b5, b6, b7;
  std::memcpy(&a0, bias + j0, sizeof(V));
  b0 = a0;
  if (kVecs == 2) std::memcpy(&b0, bias + j0 + kLanes, sizeof(V));
  a1 = a2 = a3 = a4 = a5 = a6 = a7 = a0;
  b1 = b2 = b3 = b4 = b5 = b6 = b7 = b0;
  const float* w = wt + j0;  // row k of the weights (dense: stepped, else computed)
  for (int i = 0; i < nk; ++i) {
    const int k = kDense ? i : ks[i];
    if (!kDense) w = wt + static_cast<long>(k) * ldw + j0;
    V wa, wb;
    std::memcpy(&wa, w, sizeof(V));
    const float s0 = x0[k], s1 = x1[k], s2 = x2[k], s3 = x3[k];
    a0 += s0 * wa;
    a1 += s1 * wa;
    a2 += s2 * wa;
    a3 += s3 * wa;
    if (kVecs == 2) {
      std::memcpy(&wb, w + kLanes, sizeof(V));
      b0 += s0 * wb;
      b1 += s1 * wb;
      b2 += s2 * wb;
      b3 += s3 * wb;
    }
    if (kRows == 8) {
      const float s4 = x4[k], s5 = x5[k], s6 = x6[k], s7 = x7[k];
      a4 += s4 * wa;
      a5 += s5 * wa;
      a6 += s6 * wa;
      a7 += s7 * wa;
      if (kVecs == 2) {
        b4 += s4 * wb;
        b5 += s5 * wb;
        b6 += s6 * wb;
        b7 += s7 * wb;
      }
    }
    if (kDense) w += ldw;
  }
  const V acc_a[8] = {a0, a1, a2, a3, a4, a5, a6, a7};
  const V acc_b[8] = {b0, b1, b2, b3, b4, b5, b6, b7};
  const V z = {};  // zeros of any width (a0 - a0 would be NaN where a0 is infinite)
  for (int r = 0; r < kRows; ++r) {
    V va = acc_a[r], vb = acc_b[r];
    if (relu) {
      va = va > z ? va : z;
      vb = vb > z ? vb : z;
    }
    std::memcpy(y[r] + j0, &va, sizeof(V));
    if (kVecs == 2) std::memcpy(y[r] + j0 + kLanes, &vb, sizeof(V));
  }
}

// 8 rows: wide blocks while they fit, then blocks of 8 columns (two 4-lane vectors), 4 rows at a
// time.
template <typename V, int kVecs, int kRows, bool kDense>
ECRF_ALWAYS_INLINE void Gemm8Cols(const float* const* x, const int* ks, int nk, const float* wt,
                                  int ldw, const float* bias, int ncols, bool relu,
                                  float* const* y) {
  constexpr int kWide = kVecs * static_cast<int>(sizeof(V) / sizeof(float));
  int j0 = 0;
  for (; j0 + kWide <= ncols; j0 += kWide) {
    Block<V, kVecs, kRows, kDense>(x, ks, nk, wt, ldw, bias, j0, relu, y);
    if (kRows == 4) Block<V, kVecs, kRows, kDense>(x + 4, ks, nk, wt, ldw, bias, j0, relu, y + 4);
  }
  for (; j0 < ncols; j0 += 8) {
    Block<V4, 2, 4, kDense>(x, ks, nk, wt, ldw, bias, j0, relu, y);
    Block<V4, 2, 4, kDense>(x + 4, ks, nk, wt, ldw, bias, j0, relu, y + 4);
  }
}

// ks == nullptr: every k < nk, in a loop that steps through the weights (no index loads).
template <typename V, int kVecs, int kRows>
ECRF_ALWAYS_INLINE void Gemm8Of(const float* const* x, const int* ks, int nk, const float* wt,
                                int ldw, const float* bias, int ncols, bool relu, float* const* y) {
  if (ks == nullptr) {
    Gemm8Cols<V, kVecs, kRows, true>(x, ks, nk, wt, ldw, bias, ncols, relu, y);
  } else {
    Gemm8Cols<V, kVecs, kRows, false>(x, ks, nk, wt, ldw, bias, ncols, relu, y);
  }
}

// 16 vector registers (SSE2, NEON, wasm-simd128, AVX) hold 8 accumulators of one 8-lane vector
// for 8 rows, or of two 4-lane vectors for 4 rows; AVX-512's 32 hold two vectors for 8 rows.
void Gemm8Portable(const float* const* x, const int* ks, int nk, const float* wt, int ldw,
                   const float* bias, int ncols, bool relu, float* const* y) {
  constexpr bool kNarrow = sizeof(VBuild) == 16;
  Gemm8Of<VBuild, kNarrow || sizeof(VBuild) == 64 ? 2 : 1, kNarrow ? 4 : 8>(x, ks, nk, wt, ldw,
                                                                            bias, ncols, relu, y);
}

// x86-64: the same template compiled for wider vectors. The target attributes name AVX2 and
// AVX-512F only, never FMA, so a * b + c stays two roundings as in the portable kernel.
#if defined(__x86_64__)
#define ECRF_GEMM_X86_KERNELS 1
typedef float V8 __attribute__((vector_size(32)));
typedef float V16 __attribute__((vector_size(64)));

__attribute__((target("avx2"))) void Gemm8Avx2(const float* const* x, const int* ks, int nk,
                                               const float* wt, int ldw, const float* bias,
                                               int ncols, bool relu, float* const* y) {
  Gemm8Of<V8, 1, 8>(x, ks, nk, wt, ldw, bias, ncols, relu, y);
}

__attribute__((target("avx512f"))) void Gemm8Avx512(const float* const* x, const int* ks, int nk,
                                                    const float* wt, int ldw, const float* bias,
                                                    int ncols, bool relu, float* const* y) {
  Gemm8Of<V16, 2, 8>(x, ks, nk, wt, ldw, bias, ncols, relu, y);
}
#endif

#else  // not GCC or Clang: scalar loops in the same order
void Gemm8Portable(const float* const* x, const int* ks, int nk, const float* wt, int ldw,
                   const float* bias, int ncols, bool relu, float* const* y) {
  for (int r = 0; r < 8; ++r) {
    for (int j = 0; j < ncols; ++j) y[r][j] = bias[j];
    for (int i = 0; i < nk; ++i) {
      const int k = ks != nullptr ? ks[i] : i;
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

int NonZeroColumns8(const float* const* x, int K, int* ks) {
  // A value is +-0 exactly when its bits without the sign are zero (NaN's are not), so OR-ing
  // the rows' bits tests them all at once; this part vectorises, the compaction is a short
  // branch-free loop.
  constexpr int kStep = 64;
  uint32_t any[kStep], bits[kStep];
  int nk = 0;
  for (int k0 = 0; k0 < K; k0 += kStep) {
    const int m = K - k0 < kStep ? K - k0 : kStep;
    std::memset(any, 0, sizeof(any));
    for (int r = 0; r < 8; ++r) {
      std::memcpy(bits, x[r] + k0, m * sizeof(float));
      for (int i = 0; i < m; ++i) any[i] |= bits[i] << 1;
    }
    for (int i = 0; i < m; ++i) {
      ks[nk] = k0 + i;  // written always, counted only when kept: no branch to mispredict
      nk += any[i] != 0 ? 1 : 0;
    }
  }
  return nk;
}

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

Gemm8Fn Gemm8For(GemmKernel kernel) {
  if (!GemmKernelAvailable(kernel)) return Gemm8Portable;
#if defined(ECRF_GEMM_X86_KERNELS)
  if (kernel == GemmKernel::kAvx512) return Gemm8Avx512;
  if (kernel == GemmKernel::kAvx2) return Gemm8Avx2;
#endif
  return Gemm8Portable;
}

}  // namespace dec
}  // namespace ecrf
