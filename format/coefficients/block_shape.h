// Block shapes of the block DCT: n0 x n1 x n2 (n2 varies fastest in memory), each axis a power
// of two from 1 to 32. Planes use channel x H x W blocks, lines channel x L (n0 = 1).
#ifndef ECRF_FORMAT_COEFFICIENTS_BLOCK_SHAPE_H_
#define ECRF_FORMAT_COEFFICIENTS_BLOCK_SHAPE_H_

namespace ecrf {

constexpr int kMaxBlockLength = 32;
constexpr int kMaxBlockVolume = 4096;

inline bool IsValidBlockLength(int n) {
  return n == 1 || n == 2 || n == 4 || n == 8 || n == 16 || n == 32;
}

// A legal shape: every axis a valid length and the volume at most kMaxBlockVolume (a decoder
// limit that bounds the transform's intermediate values, see SPEC.md "Integer inverse DCT").
inline bool IsValidBlockShape(const int dims[3]) {
  return IsValidBlockLength(dims[0]) && IsValidBlockLength(dims[1]) &&
         IsValidBlockLength(dims[2]) && dims[0] * dims[1] * dims[2] <= kMaxBlockVolume;
}

inline int BlockVolume(const int dims[3]) { return dims[0] * dims[1] * dims[2]; }

}  // namespace ecrf

#endif  // ECRF_FORMAT_COEFFICIENTS_BLOCK_SHAPE_H_
