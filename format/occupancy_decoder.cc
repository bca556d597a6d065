#include "format/occupancy_coder.h"

#include <cstdlib>
#include <cstring>

#include "format/entropy/range_coder.h"
#include "format/occupancy_contexts.h"

namespace ecrf {

using namespace occupancy_internal;

Status DecodeOccupancy(const uint8_t* stream, size_t size, const int res[3],
                       OccupancyContextSet set, uint8_t* bits, uint64_t* symbol_budget) {
  const int nx = res[0], ny = res[1], nz = res[2];
  std::memset(bits, 0, OccupancyBytes(res));
  // One flag per row: at most 4096^2 bytes, bounded by the caller's resolution check.
  uint8_t* row_any = static_cast<uint8_t*>(std::calloc(static_cast<size_t>(ny) * nz, 1));
  ECRF_CHECK_OR_RETURN(row_any != nullptr, kErrOutOfMemory, "OCCU: out of memory");
  const Volume volume(bits, res);
  OccupancyContexts ctx;
  RangeDecoder dec(stream, size);
  uint64_t unlimited = ~uint64_t{0};
  uint64_t& left = symbol_budget != nullptr ? *symbol_budget : unlimited;
  // Takes the symbols of what comes next (the row flag, or a flagged row's voxels) from the
  // budget before they are decoded.
  auto take = [&left](uint64_t symbols) {
    if (left < symbols) return false;
    left -= symbols;
    return true;
  };
  for (int z = 0; z < nz && !dec.HasError(); ++z) {
    for (int y = 0; y < ny; ++y) {
      bool within = take(1);
      const int any = within ? dec.DecodeBool(ctx.row[RowContext(row_any, ny, y, z)]) : 0;
      row_any[static_cast<size_t>(z) * ny + y] = static_cast<uint8_t>(any);
      if (any) within = take(static_cast<uint64_t>(nx));
      if (!within) {
        std::free(row_any);
        return Status::Error(kErrLimit, "OCCU: decode budget spent at row (y %d, z %d)", y, z);
      }
      if (!any) continue;
      const size_t base = (static_cast<size_t>(z) * ny + y) * nx;
      for (int x = 0; x < nx; ++x) {
        if (dec.DecodeBool(ctx.voxel[volume.VoxelContext(x, y, z, set)])) {
          const size_t i = base + x;
          bits[i >> 3] = static_cast<uint8_t>(bits[i >> 3] | (1u << (i & 7)));
        }
      }
    }
  }
  std::free(row_any);
  const Status s = dec.Finish();
  if (!s.ok()) return Status::Error(s.code(), "OCCU: %s", s.message());
  return Status::Ok();
}

}  // namespace ecrf
