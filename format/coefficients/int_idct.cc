#include "format/coefficients/int_idct.h"

#include <cstring>

#include "format/coefficients/block_shape.h"

namespace ecrf {
namespace {

// Normative constants (SPEC.md table "IDCT cosine tables"): K_N[j], j = 0..N.
constexpr int32_t kCos2[3] = {67108864, 47453133, 0};
constexpr int32_t kCos4[5] = {47453133, 43840978, 33554432, 18159528, 0};
constexpr int32_t kCos8[9] = {33554432, 32909693, 31000253, 27899491, 23726566,
                              18641844, 12840725, 6546145,  0};
constexpr int32_t kCos16[17] = {23726566, 23612317, 23270667, 22704908, 21920489, 20924963,
                                19727919, 18340884, 16777216, 15051974, 13181774, 11184626,
                                9079764,  6887459,  4628823,  2325610,  0};
constexpr int32_t kCos32[33] = {
    16777216, 16757007, 16696429, 16595628, 16454846, 16274424, 16054795, 15796488, 15500126,
    15166424, 14796184, 14390298, 13949745, 13475586, 12968963, 12431097, 11863283, 11266890,
    10643353, 9994176,  9320922,  8625213,  7908725,  7173184,  6420363,  5652074,  4870169,
    4076531,  3273072,  2461729,  1644455,  823219,   0};

int32_t EntryFromTable(const int32_t* table, int n, int k, int i) {
  if (k == 0) return table[n / 2];  // sqrt(2/N) cos(pi/4) = sqrt(1/N)
  // cos(pi m / 2N) with m = (2i+1)k folded into [0, N] by the cosine's symmetries.
  const int m = ((2 * i + 1) * k) % (4 * n);
  if (m <= n) return table[m];
  if (m <= 2 * n) return -table[2 * n - m];
  if (m <= 3 * n) return -table[m - 2 * n];
  return table[4 * n - m];
}

int Log2(int n) {
  int l = 0;
  while ((1 << l) < n) ++l;
  return l;
}

// Transposed matrices: rows are output samples, so the inner product runs over contiguous k.
struct IdctMatrices {
  int32_t rows[6][kMaxBlockLength * kMaxBlockLength];
  IdctMatrices() {
    for (int level = 1; level < 6; ++level) {
      const int n = 1 << level;
      for (int i = 0; i < n; ++i) {
        for (int k = 0; k < n; ++k) rows[level][i * n + k] = IdctMatrixEntry(n, k, i);
      }
    }
  }
};

const IdctMatrices& Matrices() {
  static const IdctMatrices matrices;
  return matrices;
}

inline int32_t RoundShiftClip(int64_t acc, int shift) {
  // acc is bounded by 32 * 2^31 * 2^26 < 2^62, so adding the rounding offset cannot overflow.
  int64_t v = (acc + (int64_t(1) << (shift - 1))) >> shift;
  if (v > INT32_MAX) v = INT32_MAX;
  if (v < INT32_MIN) v = INT32_MIN;
  return int32_t(v);
}

// One pass along `axis` over the lines whose other coordinates lie inside `extent` (outside it
// every value is zero and stays zero). Only the first extent[axis] coefficients of a line can be
// nonzero, so the inner product stops there.
void Pass(int32_t* data, const int dims[3], int extent[3], int axis, int shift) {
  const int n = dims[axis];
  const int kmax = extent[axis];
  const int32_t* m = Matrices().rows[Log2(n)];
  const int strides[3] = {dims[1] * dims[2], dims[2], 1};
  const int a = axis == 0 ? 1 : 0;  // the two other axes, outer a and inner b
  const int b = axis == 2 ? 1 : 2;
  int32_t in[kMaxBlockLength];
  for (int ia = 0; ia < extent[a]; ++ia) {
    for (int ib = 0; ib < extent[b]; ++ib) {
      int32_t* line = data + ia * strides[a] + ib * strides[b];
      const int stride = strides[axis];
      for (int k = 0; k < kmax; ++k) in[k] = line[k * stride];
      for (int i = 0; i < n; ++i) {
        const int32_t* row = m + i * n;
        int64_t acc = 0;
        for (int k = 0; k < kmax; ++k) acc += int64_t(row[k]) * in[k];
        line[i * stride] = RoundShiftClip(acc, shift);
      }
    }
  }
  extent[axis] = n;
}

}  // namespace

int IdctOutputFracBits(int coef_bits) {
  if (coef_bits == 8) return 8;
  if (coef_bits == 16) return 4;
  return -1;
}

const int32_t* IdctCosineTable(int n) {
  switch (n) {
    case 2:
      return kCos2;
    case 4:
      return kCos4;
    case 8:
      return kCos8;
    case 16:
      return kCos16;
    case 32:
      return kCos32;
    default:
      return nullptr;
  }
}

int32_t IdctMatrixEntry(int n, int k, int i) { return EntryFromTable(IdctCosineTable(n), n, k, i); }

void InverseDctInt(const int32_t* coeffs, const int dims[3], int coef_bits, int32_t* out) {
  const int volume = BlockVolume(dims);
  const int out_bits = IdctOutputFracBits(coef_bits);
  const int mid_bits = out_bits + kIdctGuardBits;

  // Bounding box of the nonzero coefficients.
  int extent[3] = {0, 0, 0};
  for (int i0 = 0; i0 < dims[0]; ++i0) {
    for (int i1 = 0; i1 < dims[1]; ++i1) {
      const int32_t* row = coeffs + (i0 * dims[1] + i1) * dims[2];
      for (int i2 = dims[2] - 1; i2 >= 0; --i2) {
        if (row[i2] != 0) {
          if (i0 + 1 > extent[0]) extent[0] = i0 + 1;
          if (i1 + 1 > extent[1]) extent[1] = i1 + 1;
          if (i2 + 1 > extent[2]) extent[2] = i2 + 1;
          break;
        }
      }
    }
  }
  if (extent[0] == 0) {
    std::memset(out, 0, sizeof(int32_t) * size_t(volume));
    return;
  }
  std::memcpy(out, coeffs, sizeof(int32_t) * size_t(volume));

  int axes[3];
  int num_passes = 0;
  for (int axis = 2; axis >= 0; --axis) {
    if (dims[axis] > 1) axes[num_passes++] = axis;
  }
  if (num_passes == 0) {
    out[0] = int32_t(uint32_t(out[0]) << out_bits);  // |q| < 2^15: no overflow
    return;
  }
  int frac_in = 0;
  for (int p = 0; p < num_passes; ++p) {
    const int frac_out = p == num_passes - 1 ? out_bits : mid_bits;
    Pass(out, dims, extent, axes[p], kIdctMatrixBits + frac_in - frac_out);
    frac_in = frac_out;
  }
}

}  // namespace ecrf
