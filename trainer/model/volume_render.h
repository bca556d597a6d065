// Volume rendering of a TensorfModel (TensoRF forward): ray sampling, alpha-mask empty-space
// skipping, density / appearance lookups, alpha compositing, and the batched training step with
// its hand-written backward pass.
//
// Per ray (TensoRF sample_ray / raw2alpha): t_min = clamp(entry of the aabb, near, far),
// t_i = t_min + step * (i + jitter) for i < n_samples (jitter ~ U(0,1) per ray in training, 0 at
// inference); samples outside the aabb or rejected by the alpha mask have sigma 0;
// alpha_i = 1 - exp(-sigma_i * step * distance_scale) (the last sample has dist 0);
// T_i = prod_{j<i} (1 - alpha_j + 1e-10); w_i = alpha_i T_i; colour only where w_i > weight
// threshold (other samples count as black, as in the reference); rgb = sum w c + (1 - sum w) * bg,
// clamped to [0,1]. Loss = mean over rays and channels of (rgb - target)^2.
// With the deferred head (config.head.kind, SPEC.md 7.6.1) the colour is
// rgb = W * head(S, d) + (1 - sum w) * bg, S the coloured samples' products summed with their
// weights and W their weights' sum: the head runs once per ray (deferred_shading.cc).
//
// Deviations from the reference (all below float rounding unless enabled):
//  * dist_i is the constant step (the reference takes differences of float t values);
//  * samples outside the aabb are skipped analytically before the per-point aabb test;
//  * config.early_stop_transmittance (default 0 = off) stops marching when T drops below it
//    (measured: 1e-4 leaves the colour samples unchanged and changes gradients by ~1e-4
//    relative; the tail's transmittance then reaches the background instead of black samples).
//
// Implementation (TrainStep): (1) OpenMP over rays (dynamic): per ray, candidates inside the
// aabb and the alpha mask are collected first (no feature lookups), then densities are computed
// with the grid prefetched a few samples ahead; evaluated samples go to per-thread buffers that
// persist in model.train_workspace. (2) Rays are cut into chunks of <= config.head_chunk_rows
// colour samples; per chunk the appearance products of all colour samples are gathered into
// one contiguous rows x P matrix, the head runs forward, the compositing forward/backward runs
// per ray (O(n) suffix sum), the head runs backward, and the grid gradients are scattered
// (samples bucketed by plane tile, one task per tile, each the only writer of its vertices and of
// a line of its own, the lines then summed in tile order: no atomics, and the same sums for every
// thread count).
#ifndef ECRF_TRAINER_MODEL_VOLUME_RENDER_H_
#define ECRF_TRAINER_MODEL_VOLUME_RENDER_H_

#include <cstdint>
#include <vector>

#include "trainer/model/tensorf_model.h"

namespace ecrf {
namespace trainer {

struct TrainStepStats {
  double loss = 0.0;  // mse + distortion_weight * distortion (the caller adds its other terms)
  double mse = 0.0;
  double distortion = 0.0;  // mean DistortionLoss over the rays (0 unless it is weighted in)
  long rays = 0;
  long density_samples = 0;     // samples whose density was evaluated (inside aabb and mask)
  long appearance_samples = 0;  // samples sent through the appearance head (w > threshold)
  long head_rows = 0;  // rows the head ran on: appearance samples, or rays with the deferred head
  // Wall-clock seconds of the phases (for benchmarks).
  double t_march = 0.0;      // ray sampling, mask, density forward, appearance products
  double t_head = 0.0;       // head forward + backward
  double t_composite = 0.0;  // compositing forward/backward, loss
  double t_scatter = 0.0;    // grid gradient scatter (density + appearance)
};

// Forward + backward of one batch. origins/dirs/target_rgb: n_rays x 3 (dirs are used as given;
// the reference uses unit directions). Accumulates gradients into the density / appearance grads
// and the head's grads (does not zero them, does not step Adam). Jitter is drawn from rng_seed.
// Threads with OpenMP; scratch buffers are kept in model.train_workspace across calls.
// distortion_weight > 0 adds that times the mean over rays of DistortionLoss (positions in units
// of the ray's sample cap, so a ray's samples span [0, 1] as in mip-NeRF 360's normalized
// distance; contracted distance for unbounded scenes) to the loss and its gradient.
// ray_gain (n_rays x 3, may be null: all 1) scales each ray's pixel, background included, before
// the clamp and the loss (per-image exposure codes, trainer/train/exposure_codes.h); dl_dgain
// (n_rays x 3, may be null) receives the loss's gradient with respect to those gains.
TrainStepStats TrainStep(TensorfModel& model, int n_rays, const float* origins, const float* dirs,
                         const float* target_rgb, uint64_t rng_seed, float distortion_weight = 0.f,
                         const float* ray_gain = nullptr, float* dl_dgain = nullptr);

// The most tasks TrainStep's gradient scatter runs as: one per 32x32-vertex tile of every plane of
// both grids (empty tiles are skipped).
int ScatterTaskCount(const TensorfModel& model);

// Inference (no jitter, no gradients), chunked to bound memory. rgb_out: n_rays x 3 in [0,1];
// depth_or_null: n_rays, the expected ray parameter sum_i w_i t_i (not normalized by acc).
// ray_gain (n_rays x 3, may be null: all 1) scales each pixel before the clamp, as in TrainStep.
void RenderRays(const TensorfModel& model, int n_rays, const float* origins, const float* dirs,
                float* rgb_out, float* depth_or_null, const float* ray_gain = nullptr);

// Mean squared error per channel of RenderRays's colours of n rays against rgb (n x 3), with the
// rays' exposure gains when ray_gain is not null.
double RenderMse(const TensorfModel& model, int n, const float* origins, const float* dirs,
                 const float* rgb, const float* ray_gain = nullptr);

// One evaluated sample of a ray (inside the aabb and the alpha mask), as TrainStep/RenderRays see
// it.
struct RaySampleInfo {
  float t, sigma, alpha, weight;
  bool colour;  // weight > weight_threshold: sent through the appearance head
};
// The samples the renderer evaluates along one ray (same code path), in order.
std::vector<RaySampleInfo> TraceRay(const TensorfModel& model, const float o[3], const float d[3],
                                    float jitter);

// The per-ray jitter TrainStep uses for ray `ray` of a batch with `seed` (in [0,1)).
float RayJitter(uint64_t seed, int64_t ray);

// Compositing backward for one ray, in O(n) with a suffix sum (exposed for tests).
// Given alpha[i], trans[i] = prod_{j<i} (1 - alpha_j + 1e-10) and e[i] = dL/dw_i (for the
// colour loss e_i = G . (c_i - bg) with G = dL/drgb), writes
//   dL/dalpha_i = e_i T_i - (sum_{j>i} e_j w_j) / (1 - alpha_i + 1e-10).
template <typename Real>
void CompositeBackward(int n, const Real* alpha, const Real* trans, const Real* e,
                       Real* dl_dalpha) {
  Real suffix = 0;
  for (int i = n - 1; i >= 0; --i) {
    const Real f = (Real(1) - alpha[i]) + Real(1e-10);
    dl_dalpha[i] = e[i] * trans[i] - suffix / f;
    suffix += e[i] * alpha[i] * trans[i];
  }
}

// The distortion loss of mip-NeRF 360 (Barron et al. 2022, eq. 15) for one ray, in O(n): samples
// i with weights w[i] at positions m[i] (non-decreasing), each standing for an interval of length
// delta around m[i]:
//   L = sum_i sum_j w_i w_j |m_i - m_j| + (delta / 3) sum_i w_i^2.
// It is small when the weight sits in one short stretch of the ray (a surface) and large when it
// is spread along it (floaters, fog), which real captures with few views drift into. Writes
// dL/dw_i to grad (may be null) and returns L.
template <typename Real>
Real DistortionLoss(int n, const Real* w, const Real* m, Real delta, Real* grad) {
  Real w_total = 0, wm_total = 0;
  for (int i = 0; i < n; ++i) {
    w_total += w[i];
    wm_total += w[i] * m[i];
  }
  Real loss = 0, w_before = 0, wm_before = 0;
  for (int i = 0; i < n; ++i) {
    const Real w_after = w_total - w_before - w[i];
    const Real wm_after = wm_total - wm_before - w[i] * m[i];
    // sum_j w_j |m_i - m_j|, split at i (the positions are sorted).
    const Real spread = (m[i] * w_before - wm_before) + (wm_after - m[i] * w_after);
    loss += w[i] * spread + delta / Real(3) * w[i] * w[i];
    if (grad) grad[i] = Real(2) * spread + Real(2) * delta / Real(3) * w[i];
    w_before += w[i];
    wm_before += w[i] * m[i];
  }
  return loss;
}

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_MODEL_VOLUME_RENDER_H_
