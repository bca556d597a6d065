#include "encoder/grid_dct.h"

#include <algorithm>
#include <cstring>
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

// Float copies of the orthonormal DCT matrices: m[level][k*n + j] = M[k][j].
struct FloatDctTables {
  float m[6][kMaxBlockLength * kMaxBlockLength];
  FloatDctTables() {
    for (int level = 0; level < 6; ++level) {
      const int n = 1 << level;
      const double* d = DctMatrix(n);
      for (int i = 0; i < n * n; ++i) m[level][i] = static_cast<float>(d[i]);
    }
  }
};

const FloatDctTables& Tables() {
  static const FloatDctTables tables;
  return tables;
}

// One axis of the transform by even-odd butterflies (the partial butterfly of video codecs'
// transforms): row k of M is symmetric about the middle of its axis when k is even and
// antisymmetric when k is odd, so y[k odd] = sum_{j<N/2} M[k][j] (x[j] - x[N-1-j]), and the even
// outputs are the same problem on the N/2 sums x[j] + x[N-1-j] with the rows k = 2, 6, 10, ...
// antisymmetric about N/4, and so on down to y[0] = M[0][0] * (the sum of all). For N = 16 that is
// 86 products instead of 256. The quantization-aware refresh transforms every grid twice at every
// rate-phase step: on chair-800's final model it takes 22 ms on 2 threads against 44 ms as matrix
// products (`ecrf bench train --run`, docs/results.md). The inverse (M^T) runs the same levels
// from the bottom up.
//
// Each kernel works on lanes (contiguous values of the axis's inner run) side by side, and every
// lane does the same scalar operations in the same order: this file is compiled without fused
// multiply-add (encoder/CMakeLists.txt), so every tile width, vector width and CPU gives the same
// bits, whatever the thread count.

// Lanes: 8 floats as a GCC/Clang vector type (element-wise operations, each lane its own scalar
// arithmetic), or one float. The levels are templates and their loops fully unrolled, so that
// every index is a constant and the values stay in registers.
typedef float Lanes8 __attribute__((vector_size(32)));

// (By pointer: a vector passed by value would be an ABI question without AVX, -Wpsabi.)
template <class L>
__attribute__((always_inline)) inline void LoadLanes(const float* p, L* v) {
  std::memcpy(v, p, sizeof(L));
}

template <class L>
__attribute__((always_inline)) inline void StoreLanes(float* p, const L* v) {
  std::memcpy(p, v, sizeof(L));
}

// One forward level over e[0..n): the outputs k = step, 3 step, 5 step, ... (antisymmetric rows
// over these n values) from the differences, then the next level on the sums.
template <int N, int n, int step, class L>
__attribute__((always_inline)) inline void ForwardLevel(L* e, float* __restrict y, int inner,
                                                        const float* __restrict m) {
  constexpr int h = n / 2;
  L o[h];
#pragma GCC unroll 32
  for (int j = 0; j < h; ++j) {
    const L a = e[j], b = e[n - 1 - j];
    e[j] = a + b;
    o[j] = a - b;
  }
#pragma GCC unroll 32
  for (int k = step; k < N; k += 2 * step) {
    L acc = o[0] * m[k * N];
#pragma GCC unroll 32
    for (int j = 1; j < h; ++j) acc += o[j] * m[k * N + j];
    StoreLanes(y + k * inner, &acc);
  }
  if constexpr (h > 1) {
    ForwardLevel<N, h, 2 * step>(e, y, inner, m);
  } else {
    const L dc = e[0] * m[0];
    StoreLanes(y, &dc);
  }
}

// y[k] = sum_j M[k][j] x[j], x[j] at x + j * inner, y[k] at y + k * inner.
template <int N, class L>
__attribute__((always_inline)) inline void ForwardTile(const float* __restrict x,
                                                       float* __restrict y, int inner,
                                                       const float* __restrict m) {
  L e[N];
#pragma GCC unroll 32
  for (int j = 0; j < N; ++j) LoadLanes(x + j * inner, &e[j]);
  ForwardLevel<N, N, 1>(e, y, inner, m);
}

// One inverse level: e[0..n/2) holds the even part of length n/2; adds the odd part of the rows
// k = step, 3 step, ... and unfolds e to length n; then the next level up.
template <int N, int n, class L>
__attribute__((always_inline)) inline void InverseLevel(const L* c, L* e, float* __restrict x,
                                                        int inner, const float* __restrict m) {
  constexpr int h = n / 2, step = N / n;
  L o[h];
#pragma GCC unroll 32
  for (int j = 0; j < h; ++j) {
    L acc = c[step] * m[step * N + j];
#pragma GCC unroll 32
    for (int k = 3 * step; k < N; k += 2 * step) acc += c[k] * m[k * N + j];
    o[j] = acc;
  }
#pragma GCC unroll 32
  for (int j = 0; j < h; ++j) {
    const L a = e[j], b = o[j];
    e[j] = a + b;
    e[n - 1 - j] = a - b;
  }
  if constexpr (n < N) {
    InverseLevel<N, 2 * n>(c, e, x, inner, m);
  } else {
#pragma GCC unroll 32
    for (int j = 0; j < N; ++j) StoreLanes(x + j * inner, &e[j]);
  }
}

// x[j] = sum_k M[k][j] y[k]: the levels of ForwardTile from the bottom up.
template <int N, class L>
__attribute__((always_inline)) inline void InverseTile(const float* __restrict y,
                                                       float* __restrict x, int inner,
                                                       const float* __restrict m) {
  L c[N], e[N];
#pragma GCC unroll 32
  for (int k = 0; k < N; ++k) LoadLanes(y + k * inner, &c[k]);
  e[0] = c[0] * m[0];
  InverseLevel<N, 2>(c, e, x, inner, m);
}

template <int N, class L, bool kInverse>
__attribute__((always_inline)) inline void Tile(const float* in, float* out, int inner,
                                                const float* m) {
  if (kInverse) {
    InverseTile<N, L>(in, out, inner, m);
  } else {
    ForwardTile<N, L>(in, out, inner, m);
  }
}

// `outer` independent slabs of N x inner values: out[o][k][i] = sum_j M[k][j] in[o][j][i]
// (kInverse: M^T), 8 lanes at a time, then one.
template <int N, bool kInverse>
__attribute__((always_inline)) inline void PassAxis(const float* __restrict in,
                                                    float* __restrict out, int outer, int inner,
                                                    const float* __restrict m) {
  for (int o = 0; o < outer; ++o) {
    const float* x = in + static_cast<size_t>(o) * N * inner;
    float* y = out + static_cast<size_t>(o) * N * inner;
    int i = 0;
    for (; i + 8 <= inner; i += 8) Tile<N, Lanes8, kInverse>(x + i, y + i, inner, m);
    for (; i < inner; ++i) Tile<N, float, kInverse>(x + i, y + i, inner, m);
  }
}

template <bool kInverse>
__attribute__((always_inline)) inline void DispatchAxis(const float* in, float* out, int outer,
                                                        int n, int inner) {
  const FloatDctTables& t = Tables();
  switch (n) {
    case 2:
      return PassAxis<2, kInverse>(in, out, outer, inner, t.m[1]);
    case 4:
      return PassAxis<4, kInverse>(in, out, outer, inner, t.m[2]);
    case 8:
      return PassAxis<8, kInverse>(in, out, outer, inner, t.m[3]);
    case 16:
      return PassAxis<16, kInverse>(in, out, outer, inner, t.m[4]);
    case 32:
      return PassAxis<32, kInverse>(in, out, outer, inner, t.m[5]);
  }
}

// out[c][r] = in[r][c] for rows x cols values.
inline void Transpose(const float* __restrict in, int rows, int cols, float* __restrict out) {
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) out[c * rows + r] = in[r * cols + c];
}

// A block is gathered as buf[i1][i2][i0] (i0 innermost, because a plane's channel axis is
// contiguous in the grid, so that gathering and storing a block copy runs of memory) and its
// coefficients are stored as c[i0][i1][i2]. The forward transform runs along axis 2, then 1 in
// the gathered layout, transposes, and runs along axis 0 into `coeffs`; buf0 and buf1 are
// scratch (buf0 holds the block on entry).
ECRF_MULTIVERSION
void ForwardBlock(float* buf0, float* buf1, const int n[3], float* coeffs) {
  float* cur = buf0;
  float* other = buf1;
  const int n12 = n[1] * n[2];
  if (n[2] > 1) {
    DispatchAxis<false>(cur, other, n[1], n[2], n[0]);
    std::swap(cur, other);
  }
  if (n[1] > 1) {
    DispatchAxis<false>(cur, other, 1, n[1], n[2] * n[0]);
    std::swap(cur, other);
  }
  if (n[0] > 1) {
    Transpose(cur, n12, n[0], other);
    DispatchAxis<false>(other, coeffs, 1, n[0], n12);
  } else {
    std::copy(cur, cur + n12, coeffs);
  }
}

// The inverse of ForwardBlock: coefficients c[i0][i1][i2] -> the block as buf[i1][i2][i0], in
// one of buf0/buf1 (returned). Axis 0 first, then the transposition, then axes 2 and 1.
ECRF_MULTIVERSION
float* InverseBlock(const float* coeffs, const int n[3], float* buf0, float* buf1) {
  float* cur = buf0;
  float* other = buf1;
  const int n12 = n[1] * n[2];
  if (n[0] > 1) {
    DispatchAxis<true>(coeffs, other, 1, n[0], n12);
    Transpose(other, n[0], n12, cur);
  } else {
    std::copy(coeffs, coeffs + n12, cur);
  }
  if (n[2] > 1) {
    DispatchAxis<true>(cur, other, n[1], n[2], n[0]);
    std::swap(cur, other);
  }
  if (n[1] > 1) {
    DispatchAxis<true>(cur, other, 1, n[1], n[2] * n[0]);
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
  float c[kMaxBlockVolume];
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

// Whether the first count offsets are consecutive elements (no edge replication, stride 1).
inline bool UnitRun(const long off[kMaxBlockLength], int count) {
  for (int i = 1; i < count; ++i) {
    if (off[i] != off[0] + i) return false;
  }
  return true;
}

// buf[i1][i2][i0] = the block's elements, edge-replicated where it passes the tensor's end.
inline void GatherBlock(const float* src, const int n[3], const long off[3][kMaxBlockLength],
                        float* buf) {
  // Inside the tensor a plane block's channels are one run of memory: copied as such (the
  // general path's indexed loads cost as much as the block's transform).
  const bool run = UnitRun(off[0], n[0]);
  for (int i1 = 0; i1 < n[1]; ++i1) {
    for (int i2 = 0; i2 < n[2]; ++i2) {
      const float* base = src + off[1][i1] + off[2][i2];
      float* q = buf + (i1 * n[2] + i2) * n[0];
      if (run) {
        std::copy(base + off[0][0], base + off[0][0] + n[0], q);
      } else {
        for (int i0 = 0; i0 < n[0]; ++i0) q[i0] = base[off[0][i0]];
      }
    }
  }
}

// The block's logical elements from r[i1][i2][i0] (padded positions are dropped); kAdd: padded
// copies add into the edge element they replicate (the adjoint of GatherBlock).
template <bool kAdd>
inline void StoreBlock(const float* r, const int n[3], const long off[3][kMaxBlockLength],
                       const int valid[3], float* dst) {
  const int m1 = kAdd ? n[1] : valid[1], m2 = kAdd ? n[2] : valid[2], m0 = kAdd ? n[0] : valid[0];
  const bool run = UnitRun(off[0], m0);
  for (int i1 = 0; i1 < m1; ++i1) {
    for (int i2 = 0; i2 < m2; ++i2) {
      float* base = dst + off[1][i1] + off[2][i2];
      const float* q = r + (i1 * n[2] + i2) * n[0];
      if (run) {
        float* p = base + off[0][0];
        for (int i0 = 0; i0 < m0; ++i0) {
          if (kAdd) {
            p[i0] += q[i0];
          } else {
            p[i0] = q[i0];
          }
        }
        continue;
      }
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
        ForwardBlock(buf.a, buf.b, n, dst + static_cast<size_t>(j) * vol);
      } else if (kOp == Op::kQuantize) {
        GatherBlock(src, n, off, buf.a);
        ForwardBlock(buf.a, buf.b, n, buf.c);
        QuantizeInPlace(buf.c, vol, step, rounding_offset);
        StoreBlock<false>(InverseBlock(buf.c, n, buf.a, buf.b), n, off, valid, dst);
      } else {
        const float* r = InverseBlock(src + static_cast<size_t>(j) * vol, n, buf.a, buf.b);
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
