// TensorfModel: a TensoRF VM (TensorVMSplit) radiance field with the MLP_Fea appearance head,
// its geometry (aabb, grid resolution, step size), the alpha mask, and the model-level
// operations of TensoRF training: init, upsample, alpha-mask update, shrink, ray filtering and the
// density L1 regulariser. Rendering / the training step live in volume_render.h.
#ifndef ECRF_TRAINER_MODEL_TENSORF_MODEL_H_
#define ECRF_TRAINER_MODEL_TENSORF_MODEL_H_

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "decoder/density_activation.h"
#include "format/ndc_frame.h"
#include "format/scene_header.h"
#include "trainer/model/alpha_mask.h"
#include "trainer/model/appearance_head.h"
#include "trainer/model/vm_grid.h"

namespace ecrf {
namespace trainer {

struct TensorfConfig {
  std::array<int, 3> density_ranks{{16, 16, 16}};
  std::array<int, 3> app_ranks{{48, 48, 48}};
  float init_scale = 0.1f;      // grids init: init_scale * N(0,1)
  float density_shift = -10.f;  // sigma = activation(feature + density_shift)
  DensityActivation density_activation = DensityActivation::kSoftplus;
  float distance_scale = 25.f;     // alpha = 1 - exp(-sigma * dist * distance_scale)
  float step_ratio = 0.5f;         // step = mean(aabb_size / (res - 1)) * step_ratio
  float weight_threshold = 1e-4f;  // rayMarch_weight_thres: colour only where weight > this
  float alpha_mask_threshold = 1e-4f;
  // UpdateAlphaMask computes alpha = 1 - exp(-sigma * step * alpha_mask_length_scale). The
  // reference (getDenseAlpha -> compute_alpha(xyz, self.stepSize)) uses 1; set it to
  // distance_scale for a mask that matches the rendering alpha.
  float alpha_mask_length_scale = 1.f;
  float near = 2.f;  // Blender near/far
  float far = 6.f;
  bool white_background = true;  // false: black, and in training white with probability 0.5
  int max_samples = 1000000;     // cap on samples per ray (train.py --nSamples)
  // Optional early ray termination: stop marching once the transmittance drops below this
  // (0 = off, the reference behaviour). With a value <= weight_threshold the set of colour
  // samples is unchanged and rgb changes by at most this value per ray.
  float early_stop_transmittance = 0.f;
  // TrainStep runs the head on chunks of rays with at most this many colour samples (bounds the
  // head's activation memory; the loss is separable over rays, so results do not depend on it).
  int head_chunk_rows = 32768;
  Aabb aabb;  // initial scene box (unbounded: the contracted cube [-2, 2]^3)
  // kUnbounded: world points are normalised by `roi` and contracted (decoder/contraction.h,
  // SPEC.md 7.2.1); the grids span the contracted cube, which never shrinks.
  SceneModel scene_model = SceneModel::kObject;
  Aabb roi;  // unbounded only: the region of interest, world units
  // kForward: rays are mapped into the NDC of this frame's reference camera (decoder/ndc.h,
  // SPEC.md 7.2.2) and `aabb` is an NDC box; the view direction stays the world one.
  NdcFrame ndc;
  AppearanceHeadConfig head;  // head.num_products must equal the sum of app_ranks
};

// One named parameter array (for checkpoints). shape is the storage order: planes
// [res[v], res[u], rank] (channels-last, unlike PyTorch's [1, rank, H, W]), lines [res[w], rank],
// head [size] (layout in appearance_head.h).
struct NamedArray {
  std::string name;
  std::vector<int64_t> shape;
  float* data = nullptr;
  float* grad = nullptr;
  size_t size = 0;
};

// TensoRF's ray/aabb slab test (sample_ray, filtering_rays): zero direction components are
// replaced by 1e-6; t_enter = max_a min(rate_a, rate_b), t_exit = min_a max(rate_a, rate_b).
inline void RayAabb(const Aabb& box, const float o[3], const float d[3], float* t_enter,
                    float* t_exit) {
  float tn = -INFINITY, tf = INFINITY;
  for (int a = 0; a < 3; ++a) {
    const float vec = d[a] == 0.f ? 1e-6f : d[a];
    const float ra = (box.max[a] - o[a]) / vec;
    const float rb = (box.min[a] - o[a]) / vec;
    tn = std::max(tn, std::min(ra, rb));
    tf = std::min(tf, std::max(ra, rb));
  }
  *t_enter = tn;
  *t_exit = tf;
}

// Number of samples per ray for a grid resolution (TensoRF cal_n_samples): int(|res| / step_ratio).
int CalNSamples(const std::array<int, 3>& res, float step_ratio);

class TensorfModel {
 public:
  explicit TensorfModel(const TensorfConfig& config);
  TensorfModel(const TensorfModel& other);
  TensorfModel& operator=(const TensorfModel& other);
  TensorfModel(TensorfModel&&) = default;
  TensorfModel& operator=(TensorfModel&&) = default;

  const TensorfConfig& config() const { return config_; }

  // Random init of both grids (0.1 * N(0,1)) and of the head; aabb = config.aabb; no alpha mask;
  // n_samples = min(max_samples, DefaultSamples()).
  void Initialize(const std::array<int, 3>& res, uint64_t seed);
  // Zero-filled grids of this shape (for loading checkpoints); keeps the head, drops the mask.
  // Does not change n_samples.
  void SetGeometry(const Aabb& aabb, const std::array<int, 3>& res);

  // Interpolates all planes/lines to res (align_corners=True) and updates the step size and
  // n_samples = min(max_samples, CalNSamples(res)). Grad buffers are re-allocated (zero).
  void UpsampleTo(const std::array<int, 3>& res);
  // TensoRF updateAlphaMask: alpha of the current field on a mask_res grid spanning the aabb
  // (unbounded scenes: the contracted cube, with each point's alpha over the world length of a
  // sample there)
  // (points rejected by the current mask get alpha 0), 3x3x3 max-pool, >= threshold. Installs the
  // new mask (over the current aabb) and returns the bounding box of the occupied grid points;
  // if nothing is occupied the mask is empty and the current aabb is returned.
  Aabb UpdateAlphaMask(const std::array<int, 3>& mask_res);
  // One more UpdateAlphaMask from the current density, without a shrink: on the current mask's
  // points (at most the grid's), or with mask_downscale > 1 on the grid's points coarsened by it
  // (CoarsenAlphaMask), as the updates of a run with --mask-downscale. What training does when it
  // ends. False (nothing changed) without a mask.
  bool RefreshAlphaMask(int mask_downscale);
  // TensoRF shrink: crops the grids to the vertices covering new_aabb and sets the aabb (snapped
  // to the kept vertices when there is no mask or the mask resolution differs from res).
  // Updates the step size; n_samples is unchanged (as in train.py).
  void Shrink(const Aabb& new_aabb);
  // TensoRF filtering_rays: keep[i] = 1 when ray i passes through the aabb (bbox_only, or when
  // there is no mask) or when one of n_samples inference samples along it (spacing step_size,
  // from the clamped entry point) hits the alpha mask. origins/dirs: n x 3.
  std::vector<uint8_t> FilterRays(int64_t n, const float* origins, const float* dirs,
                                  bool bbox_only, int n_samples = 256) const;

  // Removes the components (plane channel and line channel) with keep[m][r] == 0 from grid g
  // (0 density, 1 appearance; at least one per mode stays); for appearance also their basis
  // columns. The config's ranks follow. Grads are re-allocated (zero).
  void KeepComponents(int grid, const std::array<std::vector<uint8_t>, 3>& keep);
  // The head runs per sample or deferred from the next step on, with the same weights.
  void SetHeadKind(HeadKind kind) {
    config_.head.kind = kind;
    head_.set_kind(kind);
  }
  // Rays stop once their transmittance is below this (a training setting, not in the
  // checkpoint's render settings: `ecrf bench train --run` restores the run's).
  void SetEarlyStop(float transmittance) { config_.early_stop_transmittance = transmittance; }
  // Sample spacing step_ratio cells from now on; n_samples scales so that a ray covers the same
  // length (--head auto, train/head_choice.h).
  void SetStepRatio(float step_ratio);
  // A new head of this config, initialised from seed (--head auto switching to spherical
  // harmonics, train/head_choice.h); its products must be the appearance grid's.
  void ReplaceHead(const AppearanceHeadConfig& head, uint32_t seed);
  // Removes hidden units of the head (AppearanceHead::KeepHidden); the config's width follows.
  void KeepHidden(const std::vector<uint8_t>& keep1, const std::vector<uint8_t>& keep2);

  void ZeroGrads();  // density, appearance and head grads
  // Density L1 (TensoRF density_L1): adds weight * subgradient into the density grads and
  // returns the unweighted value.
  double DensityL1(float weight);

  const Aabb& aabb() const { return aabb_; }
  const std::array<int, 3>& res() const { return res_; }
  const std::array<float, 3>& units() const { return units_; }
  float step_size() const { return step_size_; }
  int n_samples() const { return n_samples_; }
  bool unbounded() const { return config_.scene_model == SceneModel::kUnbounded; }
  bool forward() const { return config_.scene_model == SceneModel::kForward; }
  // Samples per ray for the current grid: CalNSamples(res) for an object; for an unbounded scene
  // enough to cross the contracted cube (SPEC.md 7.2.1: a ray's contracted path is at most
  // 3 * 4 long, each coordinate being monotone along it).
  int DefaultSamples() const;
  void set_n_samples(int n);

  VmGrid& density() { return density_; }
  const VmGrid& density() const { return density_; }
  VmGrid& appearance() { return appearance_; }
  const VmGrid& appearance() const { return appearance_; }
  AppearanceHead& head() { return head_; }
  const AppearanceHead& head() const { return head_; }

  const AlphaMask* alpha_mask() const { return has_mask_ ? &mask_ : nullptr; }
  void SetAlphaMask(AlphaMask mask);
  void ClearAlphaMask() {
    has_mask_ = false;
    mask_ = AlphaMask();
  }

  // All trainable arrays: density.plane.{0,1,2}, density.line.{0,1,2}, appearance.plane.*,
  // appearance.line.*, head. Pointers stay valid until the next geometry change.
  std::vector<NamedArray> NamedParameters();

  // Field evaluation at world points (no mask applied): normalized coordinates and sigma.
  void Normalize(const float xyz[3], float out[3]) const;
  float Sigma(const float xyz[3]) const;

  // Scratch of the training step (owned here so buffers persist across steps; see
  // volume_render.cc). Not part of the model state; not copied.
  std::shared_ptr<void> train_workspace;

 private:
  void UpdateStepSize();

  TensorfConfig config_;
  Aabb aabb_;
  std::array<int, 3> res_{{0, 0, 0}};
  std::array<float, 3> units_{{0.f, 0.f, 0.f}};
  std::array<float, 3> inv_aabb_size_{{0.f, 0.f, 0.f}};
  float step_size_ = 0.f;
  int n_samples_ = 0;
  VmGrid density_;
  VmGrid appearance_;
  AppearanceHead head_;
  AlphaMask mask_;
  bool has_mask_ = false;
};

// d sigma / d x of ActivateDensity(a, x): softplus with PyTorch's threshold 20, or ReLU's step
// (0 at x = 0, as PyTorch's).
inline float DensityActivationGrad(DensityActivation a, float x) {
  if (a == DensityActivation::kRelu) return x > 0.f ? 1.f : 0.f;
  if (x > 20.f) return 1.f;
  const float z = std::exp(x);
  return z / (z + 1.f);
}
}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_MODEL_TENSORF_MODEL_H_
