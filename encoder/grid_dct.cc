#include "encoder/grid_dct.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "decoder/multiversion.h"
#include "encoder/coef_quantizer.h"
#include "format/coefficients/block_shape.h"
#include "format/coefficients/float_dct.h"
#include "format/vm_modes.h"

namespace ecrf {
namespace encoder {
namespace {

int Log2(int n) {
  int l = 0;
  while ((1 << l) < n) ++l;
  return l;
}

// Float copies of the orthonormal DCT matrices: m[level][k*n + j] = M[k][j] and its transpose.
struct FloatDctTables {
  float m[6][kMaxBlockLength * kMaxBlockLength];
  float mt[6][kMaxBlockLength * kMaxBlockLength];
  FloatDctTables() {
    for (int level = 0; level < 6; ++level) {
      const int n = 1 << level;
      const double* d = DctMatrix(n);
      for (int k = 0; k < n; ++k) {
        for (int j = 0; j < n; ++j) {
          m[level][k * n + j] = static_cast<float>(d[k * n + j]);
          mt[level][j * n + k] = static_cast<float>(d[k * n + j]);
        }
      }
    }
  }
};

const FloatDctTables& Tables() {
  static const FloatDctTables tables;
  return tables;
}

// out = A in along one axis of an n0 x n1 x n2 block. a[k*n + j] = A[k][j], at = A^T.
// Every output is one chain, whatever the kernel: the product with j = 0, then the products
// for j = 1, ..., N-1 added in that order, each rounded on its own (this file is compiled
// without fused multiply-add, encoder/CMakeLists.txt), so every kernel shape, vector width and
// CPU gives the same bits. The tiles keep several chains in registers at once: a chain's adds
// depend on each other, and an accumulator kept in memory waits on a store per add.

// The contiguous axis: out[r][k] = sum_j in[r][j] at[j][k], kRows rows at a time.
template <int N>
__attribute__((always_inline)) inline void PassContiguous(const float* __restrict in,
                                                          float* __restrict out, int rows,
                                                          const float* __restrict at) {
  constexpr int kRows = N >= 16 ? 4 : 8;
  int r = 0;
  for (; r + kRows <= rows; r += kRows) {
    const float* x = in + r * N;
    float acc[kRows][N];
    for (int q = 0; q < kRows; ++q)
      for (int k = 0; k < N; ++k) acc[q][k] = x[q * N] * at[k];
    for (int j = 1; j < N; ++j) {
      const float* row = at + j * N;
      for (int q = 0; q < kRows; ++q) {
        const float xj = x[q * N + j];
        for (int k = 0; k < N; ++k) acc[q][k] += xj * row[k];
      }
    }
    for (int q = 0; q < kRows; ++q)
      for (int k = 0; k < N; ++k) out[(r + q) * N + k] = acc[q][k];
  }
  for (; r < rows; ++r) {
    const float* x = in + r * N;
    float acc[N];
    for (int k = 0; k < N; ++k) acc[k] = x[0] * at[k];
    for (int j = 1; j < N; ++j) {
      const float xj = x[j];
      const float* row = at + j * N;
      for (int k = 0; k < N; ++k) acc[k] += xj * row[k];
    }
    for (int k = 0; k < N; ++k) out[r * N + k] = acc[k];
  }
}

// kOuts outputs k0..k0+kOuts-1 of one slab over a tile of kTile contiguous inner positions.
template <int N, int kOuts, int kTile>
__attribute__((always_inline)) inline void StridedTile(const float* __restrict x,
                                                       float* __restrict y, int inner, int k0,
                                                       const float* __restrict a) {
  float acc[kOuts][kTile];
  for (int q = 0; q < kOuts; ++q) {
    const float a0 = a[(k0 + q) * N];
    for (int i = 0; i < kTile; ++i) acc[q][i] = a0 * x[i];
  }
  for (int j = 1; j < N; ++j) {
    const float* xj = x + j * inner;
    for (int q = 0; q < kOuts; ++q) {
      const float akj = a[(k0 + q) * N + j];
      for (int i = 0; i < kTile; ++i) acc[q][i] += akj * xj[i];
    }
  }
  for (int q = 0; q < kOuts; ++q)
    for (int i = 0; i < kTile; ++i) y[(k0 + q) * inner + i] = acc[q][i];
}

// Axis with `outer` independent slabs, length N, inner contiguous run `inner`:
// out[o][k][i] = sum_j a[k][j] in[o][j][i].
template <int N>
__attribute__((always_inline)) inline void PassStrided(const float* __restrict in,
                                                       float* __restrict out, int outer, int inner,
                                                       const float* __restrict a) {
  constexpr int kOuts = N >= 4 ? 4 : N;
  for (int o = 0; o < outer; ++o) {
    const float* x = in + static_cast<size_t>(o) * N * inner;
    float* y = out + static_cast<size_t>(o) * N * inner;
    if (inner % 16 == 0) {
      for (int i = 0; i < inner; i += 16)
        for (int k = 0; k < N; k += kOuts) StridedTile<N, kOuts, 16>(x + i, y + i, inner, k, a);
      continue;
    }
    if (inner % 8 == 0) {
      for (int i = 0; i < inner; i += 8)
        for (int k = 0; k < N; k += kOuts) StridedTile<N, kOuts, 8>(x + i, y + i, inner, k, a);
      continue;
    }
    for (int k = 0; k < N; ++k) {
      float* yk = y + k * inner;
      const float a0 = a[k * N];
      for (int i = 0; i < inner; ++i) yk[i] = a0 * x[i];
      for (int j = 1; j < N; ++j) {
        const float akj = a[k * N + j];
        const float* xj = x + j * inner;
        for (int i = 0; i < inner; ++i) yk[i] += akj * xj[i];
      }
    }
  }
}

__attribute__((always_inline)) inline void DispatchContiguous(const float* in, float* out, int rows,
                                                              int n, const float* at) {
  switch (n) {
    case 2:
      return PassContiguous<2>(in, out, rows, at);
    case 4:
      return PassContiguous<4>(in, out, rows, at);
    case 8:
      return PassContiguous<8>(in, out, rows, at);
    case 16:
      return PassContiguous<16>(in, out, rows, at);
    case 32:
      return PassContiguous<32>(in, out, rows, at);
  }
}

__attribute__((always_inline)) inline void DispatchStrided(const float* in, float* out, int outer,
                                                           int n, int inner, const float* a) {
  switch (n) {
    case 2:
      return PassStrided<2>(in, out, outer, inner, a);
    case 4:
      return PassStrided<4>(in, out, outer, inner, a);
    case 8:
      return PassStrided<8>(in, out, outer, inner, a);
    case 16:
      return PassStrided<16>(in, out, outer, inner, a);
    case 32:
      return PassStrided<32>(in, out, outer, inner, a);
  }
}

// Separable transform of one block held as buf[i1][i2][i0] (the block's own axis order is i0,
// i1, i2: i0 innermost here because a plane's channel axis is contiguous in the grid, so that
// gathering and storing a block copy runs of memory instead of transposing them). The passes
// run along axis 2, then 1, then 0, as the coefficients are defined; `inverse` selects M^T.
// Result in one of buf0/buf1, returned.
ECRF_MULTIVERSION
float* TransformBlock(float* buf0, float* buf1, const int n[3], bool inverse) {
  const FloatDctTables& t = Tables();
  float* cur = buf0;
  float* other = buf1;
  if (n[2] > 1) {
    const int l = Log2(n[2]);
    DispatchStrided(cur, other, n[1], n[2], n[0], inverse ? t.mt[l] : t.m[l]);
    std::swap(cur, other);
  }
  if (n[1] > 1) {
    const int l = Log2(n[1]);
    DispatchStrided(cur, other, 1, n[1], n[2] * n[0], inverse ? t.mt[l] : t.m[l]);
    std::swap(cur, other);
  }
  if (n[0] > 1) {
    const int l = Log2(n[0]);
    DispatchContiguous(cur, other, n[1] * n[2], n[0], inverse ? t.m[l] : t.mt[l]);
    std::swap(cur, other);
  }
  return cur;
}

// Per-axis element offsets of block `id` with edge replication: off[a][i] for i < n[a].
// Returns the number of non-padded positions per axis in valid[a].
void BlockOffsets(const GridBlockLayout& L, int id, long off[3][kMaxBlockLength], int valid[3]) {
  int b[3];
  b[2] = id % L.blocks[2];
  b[1] = (id / L.blocks[2]) % L.blocks[1];
  b[0] = id / (L.blocks[2] * L.blocks[1]);
  for (int a = 0; a < 3; ++a) {
    const int start = b[a] * L.block[a];
    valid[a] = std::min(L.block[a], L.extent[a] - start);
    for (int i = 0; i < L.block[a]; ++i) {
      off[a][i] = static_cast<long>(std::min(start + i, L.extent[a] - 1)) * L.stride[a];
    }
  }
}

struct alignas(64) BlockBuffers {
  float a[kMaxBlockVolume];
  float b[kMaxBlockVolume];
};

// kQuantize: forward, the quantizer, inverse, with the coefficients kept in the block buffers.
enum class Op { kForward, kBackward, kInverse, kQuantize };

// QuantizeLevel(c, step, offset) * step for each of n coefficients, the test on the offset
// taken out of the loop so that it vectorizes.
inline void QuantizeInPlace(float* c, int n, double step, double rounding_offset) {
  if (rounding_offset == 0.5) {
    for (int i = 0; i < n; ++i)
      c[i] = static_cast<float>(RoundHalfAwayFromZero(double(c[i]) / step) * step);
  } else {
    for (int i = 0; i < n; ++i)
      c[i] = static_cast<float>(QuantizeLevel(double(c[i]), step, rounding_offset) * step);
  }
}

// buf[i1][i2][i0] = the block's elements, edge-replicated where it passes the tensor's end.
inline void GatherBlock(const float* src, const int n[3], const long off[3][kMaxBlockLength],
                        float* buf) {
  for (int i1 = 0; i1 < n[1]; ++i1) {
    for (int i2 = 0; i2 < n[2]; ++i2) {
      const float* base = src + off[1][i1] + off[2][i2];
      float* q = buf + (i1 * n[2] + i2) * n[0];
      for (int i0 = 0; i0 < n[0]; ++i0) q[i0] = base[off[0][i0]];
    }
  }
}

// The block's logical elements from r[i1][i2][i0] (padded positions are dropped); kAdd: padded
// copies add into the edge element they replicate (the adjoint of GatherBlock).
template <bool kAdd>
inline void StoreBlock(const float* r, const int n[3], const long off[3][kMaxBlockLength],
                       const int valid[3], float* dst) {
  const int m1 = kAdd ? n[1] : valid[1], m2 = kAdd ? n[2] : valid[2], m0 = kAdd ? n[0] : valid[0];
  for (int i1 = 0; i1 < m1; ++i1) {
    for (int i2 = 0; i2 < m2; ++i2) {
      float* base = dst + off[1][i1] + off[2][i2];
      const float* q = r + (i1 * n[2] + i2) * n[0];
      for (int i0 = 0; i0 < m0; ++i0) {
        if (kAdd) {
          base[off[0][i0]] += q[i0];
        } else {
          base[off[0][i0]] = q[i0];
        }
      }
    }
  }
}

// Coefficients in their stored order c[i0][i1][i2] from or to a block buffer b[i1][i2][i0].
inline void CoefficientsFromBuffer(const float* b, const int n[3], float* c) {
  const int n12 = n[1] * n[2];
  for (int i12 = 0; i12 < n12; ++i12)
    for (int i0 = 0; i0 < n[0]; ++i0) c[i0 * n12 + i12] = b[i12 * n[0] + i0];
}

inline void BufferFromCoefficients(const float* c, const int n[3], float* b) {
  const int n12 = n[1] * n[2];
  for (int i12 = 0; i12 < n12; ++i12)
    for (int i0 = 0; i0 < n[0]; ++i0) b[i12 * n[0] + i0] = c[i0 * n12 + i12];
}

template <Op kOp>
void RunBlocks(const float* src, const GridBlockLayout& L, const int* ids, int count, float* dst,
               double step = 0.0, double rounding_offset = 0.5) {
  const int* n = L.block;
  const int vol = L.block_volume();
  // Small jobs run serially: a parallel region costs more than a few blocks' transforms.
#pragma omp parallel if (static_cast <long>(count) * vol > 32768)
  {
    BlockBuffers buf;
    long off[3][kMaxBlockLength];
    int valid[3];
#pragma omp for schedule(dynamic, 4)
    for (int j = 0; j < count; ++j) {
      const int id = ids ? ids[j] : j;
      BlockOffsets(L, id, off, valid);
      if (kOp == Op::kForward) {
        GatherBlock(src, n, off, buf.a);
        CoefficientsFromBuffer(TransformBlock(buf.a, buf.b, n, false), n,
                               dst + static_cast<size_t>(j) * vol);
      } else if (kOp == Op::kQuantize) {
        GatherBlock(src, n, off, buf.a);
        float* c = TransformBlock(buf.a, buf.b, n, false);
        QuantizeInPlace(c, vol, step, rounding_offset);
        StoreBlock<false>(TransformBlock(c, c == buf.a ? buf.b : buf.a, n, true), n, off, valid,
                          dst);
      } else {
        BufferFromCoefficients(src + static_cast<size_t>(j) * vol, n, buf.a);
        const float* r = TransformBlock(buf.a, buf.b, n, true);
        StoreBlock<kOp == Op::kBackward>(r, n, off, valid, dst);
      }
    }
  }
}

void CheckIds(const GridBlockLayout& L, const int* ids, int count) {
  for (int j = 0; j < count; ++j) {
    if (ids[j] < 0 || ids[j] >= L.num_blocks()) {
      throw std::invalid_argument("grid_dct: block id out of range: " + std::to_string(ids[j]));
    }
  }
}

}  // namespace

GridBlockLayout MakeBlockLayout(const int extent[3], const long stride[3], const int block[3]) {
  if (!IsValidBlockShape(block)) throw std::invalid_argument("grid_dct: invalid block shape");
  GridBlockLayout L;
  for (int a = 0; a < 3; ++a) {
    if (extent[a] < 1) throw std::invalid_argument("grid_dct: extent must be >= 1");
    L.block[a] = block[a];
    L.extent[a] = extent[a];
    L.stride[a] = stride[a];
    L.blocks[a] = (extent[a] + block[a] - 1) / block[a];
    L.padded[a] = L.blocks[a] * block[a];
  }
  return L;
}

GridBlockLayout PlaneBlockLayout(const std::array<int, 3>& res, int rank, int m,
                                 const int block[3]) {
  const int w = res[kMatMode[m][0]];
  const int h = res[kMatMode[m][1]];
  const int extent[3] = {rank, h, w};
  const long stride[3] = {1, static_cast<long>(w) * rank, rank};
  return MakeBlockLayout(extent, stride, block);
}

GridBlockLayout LineBlockLayout(const std::array<int, 3>& res, int rank, int m,
                                const int block[3]) {
  if (block[0] != 1) throw std::invalid_argument("grid_dct: line blocks need n0 == 1");
  const int extent[3] = {1, rank, res[kVecMode[m]]};
  const long stride[3] = {0, 1, rank};
  return MakeBlockLayout(extent, stride, block);
}

void ForwardBlocks(const float* tensor, const GridBlockLayout& layout, float* coeffs) {
  RunBlocks<Op::kForward>(tensor, layout, nullptr, layout.num_blocks(), coeffs);
}

void BackwardBlocks(const float* dl_dcoeffs, const GridBlockLayout& layout, float* dl_dtensor) {
  RunBlocks<Op::kBackward>(dl_dcoeffs, layout, nullptr, layout.num_blocks(), dl_dtensor);
}

void InverseBlocks(const float* coeffs, const GridBlockLayout& layout, float* tensor) {
  RunBlocks<Op::kInverse>(coeffs, layout, nullptr, layout.num_blocks(), tensor);
}

void ForwardBlockList(const float* tensor, const GridBlockLayout& layout, const int* block_ids,
                      int count, float* coeffs) {
  CheckIds(layout, block_ids, count);
  RunBlocks<Op::kForward>(tensor, layout, block_ids, count, coeffs);
}

void BackwardBlockList(const float* dl_dcoeffs, const GridBlockLayout& layout, const int* block_ids,
                       int count, float* dl_dtensor) {
  CheckIds(layout, block_ids, count);
  RunBlocks<Op::kBackward>(dl_dcoeffs, layout, block_ids, count, dl_dtensor);
}

void QuantizeBlocks(const float* tensor, const GridBlockLayout& layout, double step,
                    double rounding_offset, float* out) {
  // Block by block, so that the coefficients never leave the cache: this runs on every grid
  // at every quantization-aware training step.
  RunBlocks<Op::kQuantize>(tensor, layout, nullptr, layout.num_blocks(), out, step,
                           rounding_offset);
}

}  // namespace encoder
}  // namespace ecrf
