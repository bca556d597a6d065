// Conformance vectors for coefficient decoding + integer IDCT (SPEC.md sections 3-5).
//
// Each vector is a raw range-coded stream of `blocks` coefficient blocks of one shape, decoded
// with fresh contexts of its context set (narrow: streams 1.0-1.3, wide: 1.4, neighbour: 1.5, on
// the vector's block grid) and max_abs = 127
// (8-bit) or 32767 (16-bit). The normative output is the
// concatenation of every block's InverseDctInt samples as int32 little endian; its MD5 is listed
// in tests/conformance/coefficients.md5. Shared by the conformance test and `ecrf conformance`.
#ifndef ECRF_CONFORMANCE_COEF_VECTORS_H_
#define ECRF_CONFORMANCE_COEF_VECTORS_H_

#include <cstdint>
#include <string>
#include <vector>

#include "conformance/md5.h"
#include "format/coefficients/coef_coder.h"
#include "format/coefficients/int_idct.h"
#include "format/entropy/range_coder.h"

namespace ecrf {
namespace conformance {

struct CoefVector {
  const char* name;
  BlockShape shape;
  int blocks;
  int coef_bits;
  uint32_t seed;
  int zero_percent;  // share of all-zero blocks
  int scale;         // magnitude scale of the DC coefficient
  CoefContextSet contexts;
  // The block grid the blocks lie on, raster order (b2 fastest), its product = blocks: what the
  // neighbour contexts (1.5) read; the narrow and wide sets ignore it.
  int grid[3] = {1, 1, 1};
};

inline const std::vector<CoefVector>& CoefVectors() {
  static const std::vector<CoefVector> v = {
      {"coef_16x16x16_8bit", {16, 16, 16}, 24, 8, 1, 50, 40, CoefContextSet::kNarrow},
      {"coef_1x8x8_lines_8bit", {1, 8, 8}, 96, 8, 2, 30, 30, CoefContextSet::kNarrow},
      {"coef_4x8x32_16bit", {4, 8, 32}, 12, 16, 3, 25, 9000, CoefContextSet::kNarrow},
      {"coef_1x1x32_extremes_8bit", {1, 1, 32}, 8, 8, 4, 0, 127, CoefContextSet::kNarrow},
      {"coef_32x32x4_extremes_16bit", {32, 32, 4}, 6, 16, 5, 0, 32767, CoefContextSet::kNarrow},
      {"coef_16x16x16_8bit_wide", {16, 16, 16}, 24, 8, 1, 50, 40, CoefContextSet::kWide},
      {"coef_1x8x8_lines_8bit_wide", {1, 8, 8}, 96, 8, 2, 30, 30, CoefContextSet::kWide},
      {"coef_4x8x32_16bit_wide", {4, 8, 32}, 12, 16, 3, 25, 9000, CoefContextSet::kWide},
      {"coef_32x32x4_extremes_16bit_wide", {32, 32, 4}, 6, 16, 5, 0, 32767, CoefContextSet::kWide},
      {"coef_16x16x16_8bit_neighbour",
       {16, 16, 16},
       24,
       8,
       1,
       50,
       40,
       CoefContextSet::kNeighbour,
       {2, 3, 4}},
      {"coef_1x8x8_lines_8bit_neighbour",
       {1, 8, 8},
       96,
       8,
       2,
       30,
       30,
       CoefContextSet::kNeighbour,
       {1, 8, 12}},
      {"coef_4x8x32_16bit_neighbour",
       {4, 8, 32},
       12,
       16,
       3,
       25,
       9000,
       CoefContextSet::kNeighbour,
       {3, 2, 2}},
      {"coef_32x32x4_extremes_16bit_neighbour",
       {32, 32, 4},
       6,
       16,
       5,
       0,
       32767,
       CoefContextSet::kNeighbour,
       {1, 2, 3}},
  };
  return v;
}

// A portable generator: std::*_distribution differs between standard libraries.
class Lcg {
 public:
  explicit Lcg(uint32_t seed) : state_(seed * 2654435761u + 1) {}
  uint32_t Next() {
    state_ = state_ * 6364136223846793005ull + 1442695040888963407ull;
    return uint32_t(state_ >> 33);
  }
  int Below(int n) { return int(Next() % uint32_t(n)); }

 private:
  uint64_t state_;
};

inline std::vector<int32_t> MakeCoefficients(const CoefVector& v) {
  const int volume = v.shape.Volume();
  const int32_t max_abs = v.coef_bits == 16 ? 32767 : 127;
  std::vector<int32_t> c(size_t(volume) * v.blocks, 0);
  Lcg rng(v.seed);
  const bool extremes = std::string(v.name).find("extremes") != std::string::npos;
  for (int b = 0; b < v.blocks; ++b) {
    int32_t* block = &c[size_t(b) * volume];
    if (extremes) {
      // All +max, all -max, alternating, single DC, single highest frequency, then random signs
      // of max: the worst cases of the coder's escapes and of the IDCT's ranges.
      for (int i = 0; i < volume; ++i) {
        switch (b % 6) {
          case 0:
            block[i] = max_abs;
            break;
          case 1:
            block[i] = -max_abs;
            break;
          case 2:
            block[i] = (i & 1) ? -max_abs : max_abs;
            break;
          case 3:
            block[i] = i == 0 ? max_abs : 0;
            break;
          case 4:
            block[i] = i == volume - 1 ? -max_abs : 0;
            break;
          default:
            block[i] = (rng.Next() & 1) ? max_abs : -max_abs;
        }
      }
      continue;
    }
    if (rng.Below(100) < v.zero_percent) continue;
    for (int i0 = 0; i0 < v.shape.n0; ++i0)
      for (int i1 = 0; i1 < v.shape.n1; ++i1)
        for (int i2 = 0; i2 < v.shape.n2; ++i2) {
          const int f = i0 + i1 + i2;
          const int bound = v.scale / (1 + f * f);
          int32_t m = bound > 0 ? int32_t(rng.Below(bound + 1)) : (rng.Below(8) == 0 ? 1 : 0);
          if (rng.Below(3) == 0) m = 0;
          if (m > max_abs) m = max_abs;
          block[(i0 * v.shape.n1 + i1) * v.shape.n2 + i2] = (rng.Next() & 1) ? -m : m;
        }
  }
  return c;
}

inline std::vector<uint8_t> EncodeVector(const CoefVector& v) {
  const std::vector<int32_t> c = MakeCoefficients(v);
  CoefContexts ctx;
  if (!ctx.Init(v.shape, v.contexts, v.grid, static_cast<size_t>(-1)).ok()) return {};
  RangeEncoder enc;
  for (int b = 0; b < v.blocks; ++b) EncodeCoefBlock(enc, ctx, &c[size_t(b) * v.shape.Volume()]);
  return enc.Finish();
}

// Decodes the stream, inverse transforms every block and returns the MD5 of the samples
// (int32 little endian), or "error: ..." if decoding fails.
inline std::string DecodeVectorMd5(const CoefVector& v, const std::vector<uint8_t>& stream) {
  CoefContexts ctx;
  Status s = ctx.Init(v.shape, v.contexts, v.grid, static_cast<size_t>(-1));
  if (!s.ok()) return std::string("error: ") + s.message();
  RangeDecoder dec(stream.data(), stream.size());
  const int volume = v.shape.Volume();
  const int dims[3] = {v.shape.n0, v.shape.n1, v.shape.n2};
  std::vector<int32_t> coeffs(volume), samples(volume);
  conformance::Md5 md5;
  for (int b = 0; b < v.blocks; ++b) {
    s = DecodeCoefBlock(dec, ctx, v.coef_bits == 16 ? 32767 : 127, coeffs.data());
    if (!s.ok()) return std::string("error: ") + s.message();
    InverseDctInt(coeffs.data(), dims, v.coef_bits, samples.data());
    for (int32_t x : samples) {
      const uint8_t le[4] = {uint8_t(x), uint8_t(x >> 8), uint8_t(x >> 16),
                             uint8_t(uint32_t(x) >> 24)};
      md5.Update(le, 4);
    }
  }
  s = dec.Finish();
  if (!s.ok()) return std::string("error: ") + s.message();
  return md5.HexDigest();
}

}  // namespace conformance
}  // namespace ecrf

#endif  // ECRF_CONFORMANCE_COEF_VECTORS_H_
