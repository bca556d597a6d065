// AlphaMask: TensoRF's AlphaGridMask, a 0/1 occupancy volume over an aabb used to skip empty
// space. Sampled with trilinear interpolation (grid_sample, align_corners=True, zero padding);
// a point is kept when the interpolated value is > 0, i.e. when any corner with non-zero
// interpolation weight is occupied.
#ifndef ECRF_TRAINER_MODEL_ALPHA_MASK_H_
#define ECRF_TRAINER_MODEL_ALPHA_MASK_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "trainer/data/aabb.h"

namespace ecrf {
namespace trainer {

class AlphaMask {
 public:
  AlphaMask() = default;
  // occupancy: res[2] x res[1] x res[0] bytes ([z][y][x], x fastest), 0 or 1. res[a] >= 2.
  AlphaMask(const Aabb& aabb, const std::array<int, 3>& res, std::vector<uint8_t> occupancy);

  const Aabb& aabb() const { return aabb_; }
  const std::array<int, 3>& res() const { return res_; }
  const std::vector<uint8_t>& occupancy() const { return occ_; }
  size_t count() const { return count_; }  // occupied voxels
  bool empty() const { return count_ == 0; }

  // Trilinear value at a world point (0 outside the volume's support).
  float Sample(const float xyz[3]) const;
  // Sample(xyz) > 0, with a one-lookup fast path for points strictly inside a cell.
  bool Occupied(const float xyz[3]) const;

 private:
  bool OccupiedSlow(const float idx[3]) const;

  Aabb aabb_;
  std::array<int, 3> res_{{0, 0, 0}};
  std::array<float, 3> inv_size_{{0.f, 0.f, 0.f}};  // 2 / (max - min)
  std::vector<uint8_t> occ_;
  std::vector<uint8_t> cell_any_;  // per cell (res-1 per axis): any of its 8 corners occupied
  // Per block of 4x4x4 cells (1 << kBlockShift a side): any of them in cell_any_. Training marches
  // most of its points through empty space, and this table, 1/64 of cell_any_'s size, stays in the
  // cache where cell_any_ (a byte per cell: 10 MB at 220^3) does not.
  static constexpr int kBlockShift = 2;
  std::array<int, 3> blocks_{{0, 0, 0}};
  std::vector<uint8_t> block_any_;
  size_t count_ = 0;
};

// The resolution of a mask over the same box as a grid of grid_res points whose mask points are
// at most `downscale` grid cells apart: ceil((res - 1) / downscale) + 1 points per axis (>= 2).
std::array<int, 3> AlphaMaskRes(const std::array<int, 3>& grid_res, int downscale);

// The same mask on the coarser grid of AlphaMaskRes(fine.res(), downscale), conservatively: every
// point `fine` keeps, the result keeps too. Each occupied fine point marks the corners of the
// coarse cells that contain it, so the coarse cell of any kept point has an occupied corner (its
// fine corners lie in that cell or on a face it shares). Fewer points to code (SPEC 6.3), a
// thicker shell of evaluated samples.
AlphaMask CoarsenAlphaMask(const AlphaMask& fine, int downscale);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_MODEL_ALPHA_MASK_H_
