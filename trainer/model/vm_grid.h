// VmGrid: the feature planes and lines of one TensoRF VM (vector-matrix) decomposition
// (TensorVMSplit), stored channels-last so that the rank vector of one grid vertex is contiguous.
//
// Modes (as in TensoRF): matMode = [[0,1],[0,2],[1,2]], vecMode = [2,1,0]. Plane m spans
// axes u = matMode[m][0] (grid_sample x / W) and v = matMode[m][1] (grid_sample y / H); line m
// spans axis w = vecMode[m].
//   plane m: [res[v]][res[u]][rank[m]]      line m: [res[w]][rank[m]]
// All six tensors live in one flat params() array (planes 0..2, then lines 0..2) with a
// same-shaped grads() array, so one Adam can update a whole grid.
//
// Sampling follows F.grid_sample(align_corners=True) at normalized coordinates c in [-1,1]:
// continuous index (c+1)/2*(size-1), bilinear on planes, linear on lines. Deviation: indices are
// clamped to [0, size-1] (zero padding is not reproduced); the renderer only samples points
// inside the aabb, whose indices are in range up to float rounding.
#ifndef ECRF_TRAINER_MODEL_VM_GRID_H_
#define ECRF_TRAINER_MODEL_VM_GRID_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "decoder/grid_point.h"
#include "format/vm_modes.h"

namespace ecrf {
namespace trainer {

class VmGrid {
 public:
  VmGrid() = default;

  // Allocates params and grads (zero-filled). Every res[a] must be >= 2, ranks >= 1.
  void Allocate(const std::array<int, 3>& res, const std::array<int, 3>& ranks);
  // params = scale * N(0,1), deterministic for (seed) independent of the thread count.
  void InitNormal(float scale, uint64_t seed);

  const std::array<int, 3>& res() const { return res_; }
  const std::array<int, 3>& ranks() const { return ranks_; }
  int total_rank() const { return ranks_[0] + ranks_[1] + ranks_[2]; }
  // Offset of mode m's first product inside Products() output.
  int rank_offset(int m) const { return m == 0 ? 0 : (m == 1 ? ranks_[0] : ranks_[0] + ranks_[1]); }

  size_t plane_offset(int m) const { return plane_off_[m]; }
  size_t line_offset(int m) const { return line_off_[m]; }
  size_t plane_size(int m) const {
    return static_cast<size_t>(res_[kMatMode[m][1]]) * res_[kMatMode[m][0]] * ranks_[m];
  }
  size_t line_size(int m) const { return static_cast<size_t>(res_[kVecMode[m]]) * ranks_[m]; }

  float* plane(int m) { return params_.data() + plane_off_[m]; }
  const float* plane(int m) const { return params_.data() + plane_off_[m]; }
  float* line(int m) { return params_.data() + line_off_[m]; }
  const float* line(int m) const { return params_.data() + line_off_[m]; }
  float* plane_grad(int m) { return grads_.data() + plane_off_[m]; }
  float* line_grad(int m) { return grads_.data() + line_off_[m]; }

  std::vector<float>& params() { return params_; }
  const std::vector<float>& params() const { return params_; }
  std::vector<float>& grads() { return grads_; }
  const std::vector<float>& grads() const { return grads_; }
  void ZeroGrads();

  // Element access (plane m at row y = index along v, column x = index along u).
  float& PlaneAt(int m, int y, int x, int r) {
    return params_[plane_off_[m] + (static_cast<size_t>(y) * res_[kMatMode[m][0]] + x) * ranks_[m] +
                   r];
  }
  float& LineAt(int m, int i, int r) {
    return params_[line_off_[m] + static_cast<size_t>(i) * ranks_[m] + r];
  }

  // sum_m sum_r plane_m[r](u,v) * line_m[r](w)   (TensoRF compute_densityfeature, no shift).
  float Density(const GridPoint& gp) const;
  // out[rank_offset(m) + r] = plane_m[r](u,v) * line_m[r](w)   (compute_appfeature input).
  void Products(const GridPoint& gp, float* out) const;

  // Software prefetch of everything Density/Products(gp) reads; with for_write, of the same
  // offsets in grads() (what ModeGradScatter will update). PrefetchMode: mode m only.
  void Prefetch(const GridPoint& gp, bool for_write = false) const;
  void PrefetchMode(const GridPoint& gp, int m, bool for_write) const;

  // F.interpolate(bilinear / linear, align_corners=True) of every plane and line to new_res.
  void UpsampleTo(const std::array<int, 3>& new_res);
  // Keeps vertices [lo[a], hi[a]) per axis. Grads are re-allocated (zero).
  void Crop(const std::array<int, 3>& lo, const std::array<int, 3>& hi);

  // Indices into params() of the values a grid keeping only the channels with keep[m][r] != 0
  // holds, in its own flat order (keep[m] has ranks()[m] entries). Select the same positions of
  // any array laid out like params() (an optimizer's moments) to follow KeepComponents.
  std::vector<size_t> KeptIndices(const std::array<std::vector<uint8_t>, 3>& keep) const;
  // Removes the channels with keep[m][r] == 0 from plane m and line m (at least one must stay
  // per mode). Grads are re-allocated (zero).
  void KeepComponents(const std::array<std::vector<uint8_t>, 3>& keep);

  // TensoRF density_L1: sum over m of mean|plane_m| + mean|line_m|. Adds weight * subgradient
  // (sign(x) / count, sign(0) = 0) into grads() and returns the unweighted value.
  double L1(float weight);

  // TensoRF's TV_loss_density / TV_loss_app: sum over the planes of 1e-2 * TVLoss(plane), with
  // TVLoss = 2 (sum of squared neighbour differences along v / their count + the same along u)
  // (the lines are not regularised, as in TensoRF). Adds weight * its gradient into grads() and
  // returns the unweighted value. It smooths the planes where no view constrains them, which
  // sparse real captures need (TensoRF weighs it 1.0 on LLFF, 0 on Blender scenes).
  double PlaneTotalVariation(float weight);

 private:
  void ComputeOffsets();

  std::array<int, 3> res_{{0, 0, 0}};
  std::array<int, 3> ranks_{{0, 0, 0}};
  std::array<size_t, 3> plane_off_{{0, 0, 0}};
  std::array<size_t, 3> line_off_{{0, 0, 0}};
  std::vector<float> params_;
  std::vector<float> grads_;
};

// Scatters sample gradients into one mode (plane m and line m) of a VmGrid's grads(), or into one
// tile of it. Bound to a whole mode, a task owns its plane and line; bound to a tile (BindTile),
// it owns the plane vertices of the tile and adds the line gradients of the samples whose lower
// corner lies in the tile into a line buffer of its own, which the caller sums into the grid in a
// fixed order. Either way no atomics are needed and every sum is the same whatever the thread
// count (the training step is deterministic for any thread count). Consecutive samples of a ray
// mostly touch the same vertices, so per-vertex rank vectors are accumulated in a small
// direct-mapped cache (plane slot (x&3)|((y&3)<<2), line slot i&3) and added on eviction and at
// Flush(). Call Flush() before reading grads. Cache-line aligned: tasks on different threads keep
// their slot keys in adjacent instances, which would otherwise share cache lines.
class alignas(64) ModeGradScatter {
 public:
  ModeGradScatter() = default;
  void Bind(VmGrid* grid, int mode);
  // Plane vertices x in [x0, x1), y in [y0, y1) only (x, y: the plane's axes u, v of kMatMode);
  // the line gradients of samples whose lower corner is in the tile go to line_out (line length x
  // rank floats, added to).
  void BindTile(VmGrid* grid, int mode, int x0, int x1, int y0, int y1, float* line_out);
  // This mode's share of the gradient g of Density(gp).
  void AddDensity(const GridPoint& gp, float g);
  // Gradient of this mode's products: scale * g[r] = dL/d(Products(gp)[rank_offset(mode) + r]).
  // (The deferred head's samples share their ray's g, each with its weight as the scale; 1 * g is
  // exact, so the per-sample head's sums are those of an unscaled g.)
  void AddProducts(const GridPoint& gp, const float* g, float scale = 1.f);
  void Flush();

 private:
  template <bool kDensity, int kR>
  // g_scalar: the density gradient, or the products' scale.
  void Add(const GridPoint& gp, float g_scalar, const float* g_mode);
  template <bool kDensity>
  void Dispatch(const GridPoint& gp, float g_scalar, const float* g_mode);
  void FlushPlaneSlot(int s);
  void FlushLineSlot(int s);

  VmGrid* grid_ = nullptr;
  int mode_ = 0;
  int rank_ = 0;
  int x0_ = 0, x1_ = 0, y0_ = 0, y1_ = 0;  // the tile
  float* line_out_ = nullptr;
  int plane_key_[16];
  int line_key_[4];
  std::vector<float> plane_acc_;  // 16 x rank
  std::vector<float> line_acc_;   // 4 x rank
  std::vector<float> tmp_;        // 2 x rank
};

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_MODEL_VM_GRID_H_
