// Block shapes of the coefficient coder and their scan order.
//
// The scan visits coefficients from low to high frequency so that the zeros of a quantized DCT
// block gather at the end, where a single end-of-block position codes them all. The order is a
// pure function of the shape (SPEC.md section 4, "Scan order").
#ifndef ECRF_FORMAT_COEFFICIENTS_COEF_SCAN_H_
#define ECRF_FORMAT_COEFFICIENTS_COEF_SCAN_H_

#include <cstdint>
#include <vector>

#include "format/coefficients/block_shape.h"

namespace ecrf {

// A DCT block of n0 x n1 x n2 coefficients in raster order (n2 fastest). 1D and 2D blocks set
// the leading dimensions to 1.
struct BlockShape {
  int n0 = 1;
  int n1 = 1;
  int n2 = 1;
  int Volume() const { return n0 * n1 * n2; }
};

inline BlockShape BlockShapeFromDims(const int dims[3]) {
  return BlockShape{dims[0], dims[1], dims[2]};
}

// Each dimension a power of two in [1, 32] and a volume of at most kMaxBlockVolume.
bool IsValidBlockShape(const BlockShape& shape);

// What the coefficient coder needs to know about one scan position.
struct ScanEntry {
  uint16_t raster;     // index into the [n0][n1][n2] coefficient array
  uint16_t padded;     // index into a level map with two zero planes after each dimension
  uint8_t base_band;   // frequency band of the base-level contexts
  uint8_t range_band;  // frequency band of the range-level contexts
};

constexpr int kNumBaseBands = 7;
constexpr int kNumRangeBands = 3;

// Frequency bands of a coefficient whose frequency indices sum to `frequency_sum`.
int BaseBand(int frequency_sum);
int RangeBand(int frequency_sum);

// The scan of a valid shape: raster positions sorted by i + j + k, ties in raster order.
std::vector<uint16_t> ComputeScanOrder(const BlockShape& shape);

// Scan entries plus the geometry of the padded level map for one valid shape.
struct ScanTable {
  BlockShape shape;
  std::vector<ScanEntry> entries;  // in scan order, Volume() entries
  int padded_volume = 0;           // (n0 + 2) * (n1 + 2) * (n2 + 2): neighbours up to two
                                   // steps beyond the block read zeros
  int padded_stride1 = 0;          // padded index step of the n1 axis; the n2 axis steps by 1
  int padded_stride0 = 0;          // padded index step of the n0 axis
};

// Requires IsValidBlockShape(shape).
void BuildScanTable(const BlockShape& shape, ScanTable* table);

}  // namespace ecrf

#endif  // ECRF_FORMAT_COEFFICIENTS_COEF_SCAN_H_
