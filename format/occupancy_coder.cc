#include "format/occupancy_coder.h"

#include <cstdlib>
#include <cstring>

#include "format/range_coder.h"

namespace ecrf {
namespace {

constexpr int kRowContexts = 4;
constexpr int kVoxelContexts = 16;

struct OccupancyContexts {
  uint16_t row[kRowContexts][3];
  uint16_t voxel[kVoxelContexts][3];
  OccupancyContexts() {
    for (auto& c : row) InitUniformCdf(c, 2);
    for (auto& c : voxel) InitUniformCdf(c, 2);
  }
};

// Reads already-coded voxels of a packed volume; anything outside is empty.
class Volume {
 public:
  Volume(const uint8_t* bits, const int res[3]) : bits_(bits), nx_(res[0]), ny_(res[1]) {}
  int At(int x, int y, int z) const {
    if (x < 0 || y < 0 || z < 0 || x >= nx_ || y >= ny_) return 0;
    return OccupancyBit(bits_, (static_cast<size_t>(z) * ny_ + y) * nx_ + x);
  }
  int VoxelContext(int x, int y, int z) const {
    return At(x - 1, y, z) + 2 * At(x, y - 1, z) + 4 * At(x, y, z - 1) + 8 * At(x + 1, y - 1, z);
  }

 private:
  const uint8_t* bits_;
  int nx_, ny_;
};

// row_any[z * ny + y]: whether row (y, z) has an occupied voxel.
int RowContext(const uint8_t* row_any, int ny, int y, int z) {
  const int above = y > 0 ? row_any[static_cast<size_t>(z) * ny + y - 1] : 0;
  const int behind = z > 0 ? row_any[static_cast<size_t>(z - 1) * ny + y] : 0;
  return above + 2 * behind;
}

}  // namespace

std::vector<uint8_t> EncodeOccupancy(const uint8_t* occupancy, const int res[3]) {
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
        enc.EncodeBool(row[x] != 0, ctx.voxel[volume.VoxelContext(x, y, z)]);
      }
    }
  }
  return enc.Finish();
}

Status DecodeOccupancy(const uint8_t* stream, size_t size, const int res[3], uint8_t* bits) {
  const int nx = res[0], ny = res[1], nz = res[2];
  std::memset(bits, 0, OccupancyBytes(res));
  // One flag per row: at most 4096^2 bytes, bounded by the caller's resolution check.
  uint8_t* row_any = static_cast<uint8_t*>(std::calloc(static_cast<size_t>(ny) * nz, 1));
  ECRF_CHECK_OR_RETURN(row_any != nullptr, kErrOutOfMemory, "OCCU: out of memory");
  const Volume volume(bits, res);
  OccupancyContexts ctx;
  RangeDecoder dec(stream, size);
  for (int z = 0; z < nz && !dec.HasError(); ++z) {
    for (int y = 0; y < ny; ++y) {
      const int any = dec.DecodeBool(ctx.row[RowContext(row_any, ny, y, z)]);
      row_any[static_cast<size_t>(z) * ny + y] = static_cast<uint8_t>(any);
      if (!any) continue;
      const size_t base = (static_cast<size_t>(z) * ny + y) * nx;
      for (int x = 0; x < nx; ++x) {
        if (dec.DecodeBool(ctx.voxel[volume.VoxelContext(x, y, z)])) {
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
