#include "trainer/model/small_gemm.h"

#include <algorithm>
#include <cstring>
#include <type_traits>

#if defined(__AVX512F__) || (defined(__AVX2__) && defined(__FMA__))
#include <immintrin.h>
#endif

namespace ecrf {
namespace trainer {
namespace {

// Each ISA supplies a vector type of kWidth floats, a mask for the last (partial) vector of a row,
// and kMr[nv]: rows per micro-kernel for an nv-vector-wide panel, chosen so that MR * nv
// accumulators plus the B row and one broadcast fit the register file.
#if defined(__AVX512F__)
struct Isa {
  using V = __m512;
  using Mask = __mmask16;
  static constexpr int kWidth = 16;
  static constexpr int kMaxNv = 4;
  static constexpr int kMr[kMaxNv + 1] = {0, 12, 12, 8, 6};
  static const char* Name() { return "avx512"; }
  // cols in [1, kWidth].
  static Mask TailMask(int cols) { return static_cast<Mask>((1u << cols) - 1u); }
  static V Zero() { return _mm512_setzero_ps(); }
  static V Load(const float* p) { return _mm512_loadu_ps(p); }
  static V LoadMasked(const float* p, Mask m) { return _mm512_maskz_loadu_ps(m, p); }
  static void Store(float* p, V v) { _mm512_storeu_ps(p, v); }
  static void StoreMasked(float* p, V v, Mask m) { _mm512_mask_storeu_ps(p, m, v); }
  static V Broadcast(const float* p) { return _mm512_set1_ps(*p); }
  static V Fma(V a, V b, V c) { return _mm512_fmadd_ps(a, b, c); }
};
#elif defined(__AVX2__) && defined(__FMA__)
struct Isa {
  using V = __m256;
  using Mask = __m256i;
  static constexpr int kWidth = 8;
  static constexpr int kMaxNv = 2;
  static constexpr int kMr[kMaxNv + 1] = {0, 12, 6};
  static const char* Name() { return "avx2"; }
  static Mask TailMask(int cols) {
    return _mm256_cmpgt_epi32(_mm256_set1_epi32(cols), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  }
  static V Zero() { return _mm256_setzero_ps(); }
  static V Load(const float* p) { return _mm256_loadu_ps(p); }
  // maskload/maskstore never fault on (or touch) the lanes that are off.
  static V LoadMasked(const float* p, Mask m) { return _mm256_maskload_ps(p, m); }
  static void Store(float* p, V v) { _mm256_storeu_ps(p, v); }
  static void StoreMasked(float* p, V v, Mask m) { _mm256_maskstore_ps(p, m, v); }
  static V Broadcast(const float* p) { return _mm256_broadcast_ss(p); }
  static V Fma(V a, V b, V c) { return _mm256_fmadd_ps(a, b, c); }
};
#else
// GCC/Clang vector extensions: SSE2 on any x86-64, NEON on AArch64, without naming intrinsics.
// Without FMA the product and sum round separately, which is still one fixed order per build.
struct Isa {
  typedef float V __attribute__((vector_size(16)));
  // The unaligned, aliasing view of memory that _mm_loadu_ps itself is built on.
  typedef float VU __attribute__((vector_size(16), aligned(4), may_alias));
  using Mask = int;  // number of valid floats in the last vector
  static constexpr int kWidth = 4;
  static constexpr int kMaxNv = 2;
  static constexpr int kMr[kMaxNv + 1] = {0, 8, 6};
  static const char* Name() { return "portable"; }
  static Mask TailMask(int cols) { return cols; }
  static V Zero() { return V{}; }
  static V Load(const float* p) { return *reinterpret_cast<const VU*>(p); }
  // Constant lane indices only: a loop over lanes keeps GCC from holding the accumulators in
  // registers.
  static V LoadMasked(const float* p, Mask m) {
    switch (m) {
      case 1:
        return V{p[0], 0.0f, 0.0f, 0.0f};
      case 2:
        return V{p[0], p[1], 0.0f, 0.0f};
      case 3:
        return V{p[0], p[1], p[2], 0.0f};
      default:
        return Load(p);
    }
  }
  static void Store(float* p, V v) { *reinterpret_cast<VU*>(p) = v; }
  static void StoreMasked(float* p, V v, Mask m) {
    switch (m) {
      case 3:
        p[2] = v[2];
        [[fallthrough]];
      case 2:
        p[1] = v[1];
        [[fallthrough]];
      case 1:
        p[0] = v[0];
        break;
      default:
        Store(p, v);
    }
  }
  static V Broadcast(const float* p) { return V{*p, *p, *p, *p}; }
  static V Fma(V a, V b, V c) { return a * b + c; }
};
#endif

using V = Isa::V;
using Mask = Isa::Mask;
constexpr int kW = Isa::kWidth;

// Rows of A per block; a multiple of every kMr so the micro-kernels tile it.
constexpr int kMc = 24;
// Longest K block; also sizes the stack buffer for packed A.
constexpr int kMaxKc = 256;
// K is split only once its block of B (kc rows x N columns) would pass this many bytes. Longer
// blocks amortise each C tile's load and store; B streams well enough from L2 that keeping it in
// L1 (48 KiB) does not pay: measured on Zen 5, only the 144- and 150-column, K = 256 products gain.
constexpr int kBBudget = 128 << 10;

// C tile (MR rows x NV vectors) (+)= A tile * B panel over kc steps. A(i,p) is a[i*lda + p]
// (row-major, kTransA false) or a[p*lda + i] (transposed or packed, kTransA true). Only the last
// vector of each row is masked, by `tail` (all ones unless the panel ends at column N).
template <int MR, int NV, bool kTransA>
void MicroKernel(int kc, const float* a, std::ptrdiff_t lda, const float* b, std::ptrdiff_t ldb,
                 float* c, std::ptrdiff_t ldc, Mask tail, bool load_c) {
  V acc[MR][NV];
#pragma GCC unroll 32
  for (int i = 0; i < MR; ++i) {
#pragma GCC unroll 4
    for (int v = 0; v < NV; ++v) {
      const float* ci = c + i * ldc + v * kW;
      acc[i][v] = !load_c ? Isa::Zero() : v + 1 < NV ? Isa::Load(ci) : Isa::LoadMasked(ci, tail);
    }
  }
  for (int p = 0; p < kc; ++p) {
    V bv[NV];
    const float* bp = b + p * ldb;
#pragma GCC unroll 4
    for (int v = 0; v < NV; ++v) {
      bv[v] = v + 1 < NV ? Isa::Load(bp + v * kW) : Isa::LoadMasked(bp + v * kW, tail);
    }
#pragma GCC unroll 32
    for (int i = 0; i < MR; ++i) {
      const V ai = Isa::Broadcast(kTransA ? a + p * lda + i : a + i * lda + p);
#pragma GCC unroll 4
      for (int v = 0; v < NV; ++v) acc[i][v] = Isa::Fma(ai, bv[v], acc[i][v]);
    }
  }
#pragma GCC unroll 32
  for (int i = 0; i < MR; ++i) {
#pragma GCC unroll 4
    for (int v = 0; v < NV; ++v) {
      float* ci = c + i * ldc + v * kW;
      if (v + 1 < NV) {
        Isa::Store(ci, acc[i][v]);
      } else {
        Isa::StoreMasked(ci, acc[i][v], tail);
      }
    }
  }
}

// Runs one NV-vector panel over `rows` rows of the A block: full MR-row tiles, then the leftover
// rows in tiles of 8, 4, 3, 2 or 1. Fewer kernel instantiations than one per leftover count, yet
// the common small tails (M = 3, 27 % 8 = 3) still get enough accumulators to hide FMA latency.
// (The `MR > 8 ? 8 : 1` spellings only keep unused tile sizes from being instantiated.)
template <int NV, bool kTransA>
void Panel(int rows, int kc, const float* a, std::ptrdiff_t lda, const float* b, std::ptrdiff_t ldb,
           float* c, std::ptrdiff_t ldc, Mask tail, bool load_c) {
  constexpr int MR = Isa::kMr[NV];
  const std::ptrdiff_t a_step = kTransA ? 1 : lda;
  int i = 0;
  auto run = [&](auto tile_rows) {
    constexpr int kRows = decltype(tile_rows)::value;
    MicroKernel<kRows, NV, kTransA>(kc, a + i * a_step, lda, b, ldb, c + i * ldc, ldc, tail,
                                    load_c);
    i += kRows;
  };
  while (rows - i >= MR) run(std::integral_constant<int, MR>());
  while (i < rows) {
    const int left = rows - i;
    if (MR > 8 && left >= 8) {
      run(std::integral_constant<int, (MR > 8 ? 8 : 1)>());
    } else if (MR > 4 && left >= 4) {
      run(std::integral_constant<int, (MR > 4 ? 4 : 1)>());
    } else if (left == 3) {
      run(std::integral_constant<int, 3>());
    } else if (left == 2) {
      run(std::integral_constant<int, 2>());
    } else {
      run(std::integral_constant<int, 1>());
    }
  }
}

template <bool kTransA>
void PanelAnyNv(int nv, int rows, int kc, const float* a, std::ptrdiff_t lda, const float* b,
                std::ptrdiff_t ldb, float* c, std::ptrdiff_t ldc, Mask tail, bool load_c) {
  switch (nv) {
    case 1:
      return Panel<1, kTransA>(rows, kc, a, lda, b, ldb, c, ldc, tail, load_c);
    case 2:
      return Panel<2, kTransA>(rows, kc, a, lda, b, ldb, c, ldc, tail, load_c);
    case 3:
      if constexpr (Isa::kMaxNv >= 3) {
        return Panel<3, kTransA>(rows, kc, a, lda, b, ldb, c, ldc, tail, load_c);
      }
      break;
    case 4:
      if constexpr (Isa::kMaxNv >= 4) {
        return Panel<4, kTransA>(rows, kc, a, lda, b, ldb, c, ldc, tail, load_c);
      }
      break;
  }
}

}  // namespace

void SmallGemm(int M, int N, int K, const float* a, std::ptrdiff_t a_row, std::ptrdiff_t a_col,
               const float* b, std::ptrdiff_t ldb, float* c, std::ptrdiff_t ldc, bool accumulate) {
  if (M <= 0 || N <= 0) return;
  if (K <= 0) {
    if (!accumulate) {
      for (int i = 0; i < M; ++i) std::fill_n(c + i * ldc, N, 0.0f);
    }
    return;
  }
  // Columns split into panels of at most kMaxNv vectors, sized as evenly as possible so that no
  // panel is left with a narrow, register-starved tile (150 columns: 4 + 3 + 3 vectors).
  const int nvec = (N + kW - 1) / kW;
  const int npanels = (nvec + Isa::kMaxNv - 1) / Isa::kMaxNv;
  const Mask full = Isa::TailMask(kW);
  const Mask tail = Isa::TailMask(N - (nvec - 1) * kW);
  // Row-major A (a_col = 1) and transposed A (a_row = 1) feed the kernels in place; packing the
  // transposed case measured slower, its copy costing more than its better locality gains. Only a
  // doubly strided A, which none of our callers use, goes through the packing buffer.
  const bool trans_a = a_col != 1;
  const bool pack = trans_a && a_row != 1;
  alignas(64) float packed[kMc * kMaxKc];
  const int row_bytes = nvec * kW * static_cast<int>(sizeof(float));
  const int kc_cap = std::clamp(kBBudget / row_bytes, 16, pack ? kMaxKc : kBBudget);
  const int kblocks = (K + kc_cap - 1) / kc_cap;
  const int kc = (K + kblocks - 1) / kblocks;
  for (int p0 = 0; p0 < K; p0 += kc) {
    const int kcur = std::min(kc, K - p0);
    const bool load_c = accumulate || p0 > 0;
    for (int i0 = 0; i0 < M; i0 += kMc) {
      const int rows = std::min(kMc, M - i0);
      const float* ablk = a + i0 * a_row + p0 * a_col;
      if (pack) {
        for (int p = 0; p < kcur; ++p) {
          for (int i = 0; i < rows; ++i) packed[p * kMc + i] = ablk[p * a_col + i * a_row];
        }
      }
      int v0 = 0;
      for (int jp = 0; jp < npanels; ++jp) {
        const int nv = nvec / npanels + (jp < nvec % npanels ? 1 : 0);
        const Mask m = jp + 1 == npanels ? tail : full;
        const float* bp = b + p0 * ldb + v0 * kW;
        float* cp = c + i0 * ldc + v0 * kW;
        if (pack) {
          PanelAnyNv<true>(nv, rows, kcur, packed, kMc, bp, ldb, cp, ldc, m, load_c);
        } else if (trans_a) {
          PanelAnyNv<true>(nv, rows, kcur, ablk, a_col, bp, ldb, cp, ldc, m, load_c);
        } else {
          PanelAnyNv<false>(nv, rows, kcur, ablk, a_row, bp, ldb, cp, ldc, m, load_c);
        }
        v0 += nv;
      }
    }
  }
}

const char* SmallGemmIsa() { return Isa::Name(); }

}  // namespace trainer
}  // namespace ecrf
