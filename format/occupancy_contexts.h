// The context model shared by the occupancy encoder and decoder (SPEC.md 4.2): both halves
// must update the same adaptive CDFs in the same order.
#ifndef ECRF_FORMAT_OCCUPANCY_CONTEXTS_H_
#define ECRF_FORMAT_OCCUPANCY_CONTEXTS_H_

#include <cstddef>
#include <cstdint>

#include "format/entropy/range_coder.h"
#include "format/occupancy_coder.h"

namespace ecrf {
namespace occupancy_internal {

constexpr int kRowContexts = 4;
constexpr int kVoxelContexts = 16;       // narrow set: four neighbours
constexpr int kWideVoxelContexts = 512;  // wide set: nine

struct OccupancyContexts {
  uint16_t row[kRowContexts][3];
  uint16_t voxel[kWideVoxelContexts][3];
  OccupancyContexts() {
    for (auto& c : row) InitUniformCdf(c, 2);
    for (auto& c : voxel) InitUniformCdf(c, 2);
  }
};

// Reads already-coded voxels of a packed volume; anything outside is empty.
class Volume {
 public:
  Volume(const uint8_t* bits, const int res[3]) : bits_(bits), nx_(res[0]), ny_(res[1]) {}
  // z < the slice being coded: only the (y + 1) read of the previous slice looks ahead in y.
  int At(int x, int y, int z) const {
    if (x < 0 || y < 0 || z < 0 || x >= nx_ || y >= ny_) return 0;
    return OccupancyBit(bits_, (static_cast<size_t>(z) * ny_ + y) * nx_ + x);
  }
  int VoxelContext(int x, int y, int z, OccupancyContextSet set) const {
    const int narrow =
        At(x - 1, y, z) + 2 * At(x, y - 1, z) + 4 * At(x, y, z - 1) + 8 * At(x + 1, y - 1, z);
    if (set == OccupancyContextSet::kNarrow) return narrow;
    return narrow + 16 * At(x + 1, y, z - 1) + 32 * At(x - 1, y - 1, z) + 64 * At(x, y + 1, z - 1) +
           128 * At(x - 1, y, z - 1) + 256 * At(x, y - 1, z - 1);
  }

 private:
  const uint8_t* bits_;
  int nx_, ny_;
};

// row_any[z * ny + y]: whether row (y, z) has an occupied voxel.
inline int RowContext(const uint8_t* row_any, int ny, int y, int z) {
  const int above = y > 0 ? row_any[static_cast<size_t>(z) * ny + y - 1] : 0;
  const int behind = z > 0 ? row_any[static_cast<size_t>(z - 1) * ny + y] : 0;
  return above + 2 * behind;
}

}  // namespace occupancy_internal
}  // namespace ecrf

#endif  // ECRF_FORMAT_OCCUPANCY_CONTEXTS_H_
