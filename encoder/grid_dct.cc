#include "encoder/grid_dct.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "decoder/multiversion.h"
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
// Axis 2 (contiguous): out[r][k] = sum_j in[r][j] at[j][k] (axpy over k, contiguous).
template <int N>
__attribute__((always_inline)) inline void PassAxis2(const float* __restrict in,
                                                     float* __restrict out, int rows,
                                                     const float* __restrict at) {
  for (int r = 0; r < rows; ++r) {
    const float* x = in + r * N;
    float* y = out + r * N;
    float acc[N];
    for (int k = 0; k < N; ++k) acc[k] = x[0] * at[k];
    for (int j = 1; j < N; ++j) {
      const float xj = x[j];
      const float* row = at + j * N;
      for (int k = 0; k < N; ++k) acc[k] += xj * row[k];
    }
    for (int k = 0; k < N; ++k) y[k] = acc[k];
  }
}

// Axis with `outer` independent slabs, length N, inner contiguous run `inner`:
// out[o][k][i] = sum_j a[k][j] in[o][j][i].
template <int N>
__attribute__((always_inline)) inline void PassStrided(const float* __restrict in,
                                                       float* __restrict out, int outer, int inner,
                                                       const float* __restrict a) {
  for (int o = 0; o < outer; ++o) {
    const float* x = in + static_cast<size_t>(o) * N * inner;
    float* y = out + static_cast<size_t>(o) * N * inner;
    for (int k = 0; k < N; ++k) {
      float* yk = y + k * inner;
      const float a0 = a[k * N];
#pragma omp simd
      for (int i = 0; i < inner; ++i) yk[i] = a0 * x[i];
      for (int j = 1; j < N; ++j) {
        const float akj = a[k * N + j];
        const float* xj = x + j * inner;
#pragma omp simd
        for (int i = 0; i < inner; ++i) yk[i] += akj * xj[i];
      }
    }
  }
}

__attribute__((always_inline)) inline void DispatchAxis2(const float* in, float* out, int rows,
                                                         int n, const float* at) {
  switch (n) {
    case 2:
      return PassAxis2<2>(in, out, rows, at);
    case 4:
      return PassAxis2<4>(in, out, rows, at);
    case 8:
      return PassAxis2<8>(in, out, rows, at);
    case 16:
      return PassAxis2<16>(in, out, rows, at);
    case 32:
      return PassAxis2<32>(in, out, rows, at);
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

// Separable transform of one block; `inverse` selects M^T. Result in *result (one of buf0/buf1).
ECRF_MULTIVERSION
float* TransformBlock(float* buf0, float* buf1, const int n[3], bool inverse) {
  const FloatDctTables& t = Tables();
  float* cur = buf0;
  float* other = buf1;
  if (n[2] > 1) {
    const int l = Log2(n[2]);
    DispatchAxis2(cur, other, n[0] * n[1], n[2], inverse ? t.m[l] : t.mt[l]);
    std::swap(cur, other);
  }
  if (n[1] > 1) {
    const int l = Log2(n[1]);
    DispatchStrided(cur, other, n[0], n[1], n[2], inverse ? t.mt[l] : t.m[l]);
    std::swap(cur, other);
  }
  if (n[0] > 1) {
    const int l = Log2(n[0]);
    DispatchStrided(cur, other, 1, n[0], n[1] * n[2], inverse ? t.mt[l] : t.m[l]);
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

enum class Op { kForward, kBackward, kInverse };

template <Op kOp>
void RunBlocks(const float* src, const GridBlockLayout& L, const int* ids, int count, float* dst) {
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
        // Loop order i1, i2, i0: planes have the channel axis (a0) contiguous in memory.
        const int n12 = n[1] * n[2];
        for (int i1 = 0; i1 < n[1]; ++i1) {
          for (int i2 = 0; i2 < n[2]; ++i2) {
            const float* base = src + off[1][i1] + off[2][i2];
            float* q = buf.a + i1 * n[2] + i2;
            for (int i0 = 0; i0 < n[0]; ++i0) q[i0 * n12] = base[off[0][i0]];
          }
        }
        const float* r = TransformBlock(buf.a, buf.b, n, false);
        std::copy(r, r + vol, dst + static_cast<size_t>(j) * vol);
      } else {
        const float* c = src + static_cast<size_t>(j) * vol;
        std::copy(c, c + vol, buf.a);
        const float* r = TransformBlock(buf.a, buf.b, n, true);
        if (kOp == Op::kBackward) {
          // Padded copies add into the edge element they replicate (serial within the block).
          const int n12 = n[1] * n[2];
          for (int i1 = 0; i1 < n[1]; ++i1) {
            for (int i2 = 0; i2 < n[2]; ++i2) {
              float* base = dst + off[1][i1] + off[2][i2];
              const float* q = r + i1 * n[2] + i2;
              for (int i0 = 0; i0 < n[0]; ++i0) base[off[0][i0]] += q[i0 * n12];
            }
          }
        } else {
          const int n12 = n[1] * n[2];
          for (int i1 = 0; i1 < valid[1]; ++i1) {
            for (int i2 = 0; i2 < valid[2]; ++i2) {
              float* base = dst + off[1][i1] + off[2][i2];
              const float* q = r + i1 * n[2] + i2;
              for (int i0 = 0; i0 < valid[0]; ++i0) base[off[0][i0]] = q[i0 * n12];
            }
          }
        }
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

}  // namespace encoder
}  // namespace ecrf
