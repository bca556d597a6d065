// Coding of the occupancy (alpha) mask of the OCCU chunk (SPEC.md 6.3): a res[0] x res[1] x
// res[2] binary volume, scanned z, then y, then x (x fastest). Each row of x first gets a flag
// "row has an occupied voxel" (context: the same flag of the row above and of the row in the
// previous slice); only occupied rows code their voxels, each with a context made of
// already-coded neighbours: four in the narrow context set of streams 1.0-1.4, nine in the wide
// set of 1.5 (five of them in the previous slice). Empty space therefore costs almost nothing and
// decodes fast.
#ifndef ECRF_FORMAT_OCCUPANCY_CODER_H_
#define ECRF_FORMAT_OCCUPANCY_CODER_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "format/status.h"

namespace ecrf {

// Bits are packed [z][y][x], x fastest: voxel i is bit (i % 8) of byte i / 8 (LSB first).
inline bool OccupancyBit(const uint8_t* bits, size_t i) { return (bits[i >> 3] >> (i & 7)) & 1; }
inline size_t OccupancyBytes(const int res[3]) {
  return (static_cast<size_t>(res[0]) * res[1] * res[2] + 7) / 8;
}

// The `contexts` field of an OCCU chunk (SPEC.md 6.3). Wide (1.5): the narrow set's four
// neighbours plus (x - 1, y - 1, z) and four of the previous slice; a trained mask's surface
// continues from slice to slice, so the wide set codes chair's and mic's masks in 20% fewer bytes.
enum class OccupancyContextSet : uint16_t { kNarrow = 0, kWide = 1 };
constexpr uint16_t kMaxOccupancyContextSet = 1;
// The container minor version a stream with a wide OCCU chunk needs at least (SPEC.md 2.1).
constexpr uint8_t kWideOccupancyContextsMinVersionMinor = 5;

// occupancy: res[2]*res[1]*res[0] bytes, nonzero = occupied. Returns the range-coded stream.
std::vector<uint8_t> EncodeOccupancy(const uint8_t* occupancy, const int res[3],
                                     OccupancyContextSet set = OccupancyContextSet::kNarrow);

// bits: OccupancyBytes(res) bytes, which the decoder overwrites. The caller has checked res
// against the limits. kErrTruncated / kErrCorrupt for a bad stream. symbol_budget (optional): the
// symbols the caller lets this chunk decode, decreased by those it does; a row whose voxels would
// take more is not decoded (kErrLimit), so the work is bounded before it is spent (SPEC.md 8).
Status DecodeOccupancy(const uint8_t* stream, size_t size, const int res[3],
                       OccupancyContextSet set, uint8_t* bits, uint64_t* symbol_budget = nullptr);

}  // namespace ecrf

#endif  // ECRF_FORMAT_OCCUPANCY_CODER_H_
