// The encoder half of the OCCU chunk (SPEC.md 4.2).
#include "format/occupancy_coder.h"

#include <cstdlib>
#include <cstring>

#include "format/entropy/range_coder.h"
#include "format/occupancy_contexts.h"

namespace ecrf {

using namespace occupancy_internal;

std::vector<uint8_t> EncodeOccupancy(const uint8_t* occupancy, const int res[3],
                                     OccupancyContextSet set) {
  const int nx = res[0], ny = res[1], nz = res[2];
  std::vector<uint8_t> bits(OccupancyBytes(res), 0);
  for (size_t i = 0, n = static_cast<size_t>(nx) * ny * nz; i < n; ++i) {
    if (occupancy[i]) bits[i >> 3] = static_cast<uint8_t>(bits[i >> 3] | (1u << (i & 7)));
  }
  const Volume volume(bits.data(), res);
  std::vector<uint8_t> row_any(static_cast<size_t>(ny) * nz, 0);
  OccupancyContexts ctx;
  RangeEncoder enc;
  for (int z = 0; z < nz; ++z) {
    for (int y = 0; y < ny; ++y) {
      const uint8_t* row = occupancy + (static_cast<size_t>(z) * ny + y) * nx;
      int any = 0;
      for (int x = 0; x < nx && !any; ++x) any = row[x] != 0;
      enc.EncodeBool(any, ctx.row[RowContext(row_any.data(), ny, y, z)]);
      row_any[static_cast<size_t>(z) * ny + y] = static_cast<uint8_t>(any);
      if (!any) continue;
      for (int x = 0; x < nx; ++x) {
        enc.EncodeBool(row[x] != 0, ctx.voxel[volume.VoxelContext(x, y, z, set)]);
      }
    }
  }
  return enc.Finish();
}

}  // namespace ecrf
