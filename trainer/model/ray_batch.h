// Internal to trainer/model (volume_render.cc and deferred_shading.cc): the scratch of one batch
// of rays in TrainStep and RenderRays (Workspace), the loss a step takes of each ray, the
// compositing forward and backward of one ray, and the deferred head's part of a step.
#ifndef ECRF_TRAINER_MODEL_RAY_BATCH_H_
#define ECRF_TRAINER_MODEL_RAY_BATCH_H_

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "trainer/model/appearance_head.h"
#include "trainer/model/ray_samples.h"
#include "trainer/model/volume_render.h"

namespace ecrf {
namespace trainer {
namespace batch {

using march::Candidate;
using march::SampleRec;

constexpr int kMinParallelRays = 64;  // smaller batches run on one thread (no fork/join cost)

// Grows v to at least n elements and never shrinks it: a shrink followed by a regrow would
// zero-fill the regrown part again (the chunks of one batch have different sizes).
inline void EnsureSize(std::vector<float>& v, size_t n) {
  if (v.size() < n) v.resize(n);
}

// A ray's composited colour and the sums its backward pass reads again.
struct RayComposite {
  float c[3] = {0.f, 0.f, 0.f};
  float acc = 0.f;                       // accumulated opacity
  double w_total = 0.0, wm_total = 0.0;  // distortion loss: the sums of w and w * m
};

struct RayRec {
  int tid;  // thread whose sample buffer holds the samples
  int count;
  size_t offset;  // into that buffer
  int64_t app_start;
  int app_count;
};

// One thread's sample buffers. Cache-line aligned: every push_back writes the vector's end
// pointer, and two threads' vector headers on one line made marching scale 1.3x on 2 threads.
struct alignas(64) ThreadSamples {
  std::vector<SampleRec> samples;
  std::vector<Candidate> candidates;  // one ray at a time
};

// Scratch of one batch; reused across steps so steady-state steps do not allocate.
struct Workspace {
  std::vector<ThreadSamples> per_thread;
  std::vector<RayRec> rays;
  std::vector<float> products, viewdirs, rgb, dl_drgb, dl_dproducts;
  // The deferred head (DeferredChunk): one row per ray with a coloured sample.
  struct HeadRay {
    int row = -1;                  // the ray's row of the head matrices, or -1: no coloured sample
    float weight = 0.f;            // the sum of its coloured samples' weights
    float g[3] = {0.f, 0.f, 0.f};  // dL/d(composited colour)
  };
  std::vector<HeadRay> head_rays;             // per ray of the chunk
  std::vector<RayComposite> head_composites;  // per ray of the chunk, forward to backward
  std::vector<float> ray_products, ray_viewdirs, ray_rgb, ray_dl_drgb, ray_dl_dproducts;
  // The gradient scatter (ScatterChunk): per (grid, mode), density modes 0-2 then appearance
  // modes 0-2, the chunk's samples bucketed by plane tile in ray order, and each tile's line sums.
  struct ScatterEntry {
    const GridPoint* gp;
    float g;  // density: dL/d(feature); appearance: the scale of dprod
    // Appearance: the sample's products gradient at this mode's offset (times g); the deferred
    // head's samples point at their ray's, each scaled by its weight.
    const float* dprod;
  };
  struct ModeTiles {
    int tiles_x = 0, tiles_y = 0, line_floats = 0;
    std::vector<std::vector<ScatterEntry>> lists;  // per tile
    std::vector<float> line_sums;                  // per tile: line length x rank
  };
  ModeTiles tiles[6];
  struct TileTask {
    int mode_task, tile;
    size_t entries;
  };
  std::vector<TileTask> tile_tasks;
  std::vector<ModeGradScatter> scatter;  // one per tile task

  void Prepare(int n_rays, int threads) {
    if (static_cast<int>(per_thread.size()) < threads) per_thread.resize(threads);
    for (auto& t : per_thread) t.samples.clear();
    rays.resize(n_rays);
  }
  const SampleRec* SamplesOf(const RayRec& rr) const {
    return per_thread[rr.tid].samples.data() + rr.offset;
  }
  SampleRec* SamplesOf(const RayRec& rr) { return per_thread[rr.tid].samples.data() + rr.offset; }
};

// What the loss of a step needs of each ray, the same for all its rays.
struct RayLoss {
  const float* target_rgb;  // n_rays x 3
  const float* ray_gain;    // n_rays x 3, or null: all 1
  float* dl_dgain;          // n_rays x 3, or null: not wanted
  bool white;               // the background is white (else black)
  DensityActivation activation;
  float grad_scale;  // d(mean squared error)/d(diff) per unit diff: 2 / (3 n_rays)
  // The distortion loss (DistortionLoss, inlined into CompositeBackward): positions
  // m = s / n_samples, intervals 1 / n_samples.
  bool distortion_on;
  double inv_n;
  double distortion_scale;  // distortion_weight / n_rays
};

// Compositing forward of one ray: the weights w = alpha * trans summed into colour and opacity.
// The ray's appearance samples have rows row0 + app of rgb (null: no colour, the deferred head's).
inline RayComposite CompositeForward(const RayLoss& loss, const SampleRec* s, int count,
                                     const float* rgb_rows, int64_t row0) {
  RayComposite rc;
  for (int k = 0; k < count; ++k) {
    const float w = s[k].alpha * s[k].trans;
    rc.acc += w;
    if (loss.distortion_on) {
      rc.w_total += w;
      rc.wm_total += w * (s[k].s * loss.inv_n);
    }
    if (s[k].app >= 0 && rgb_rows != nullptr) {
      const float* rgb = rgb_rows + 3 * (row0 + s[k].app);
      rc.c[0] += w * rgb[0];
      rc.c[1] += w * rgb[1];
      rc.c[2] += w * rgb[2];
    }
  }
  return rc;
}

// The photometric loss of ray r: the background and the gain applied, the pixel clamped, its
// squared errors added to sse (the caller's reduction variable, channel by channel), g set to
// dL/d(composited colour) and, when asked, dL/dgain written.
inline void PixelLoss(const RayLoss& loss, int r, RayComposite& rc, float g[3], double& sse) {
  for (int ch = 0; ch < 3; ++ch) {
    if (loss.white) rc.c[ch] += 1.f - rc.acc;
    // 1 * x is exact, so rays without a gain train bit for bit as before.
    const float gain = loss.ray_gain ? loss.ray_gain[3 * r + ch] : 1.f;
    const float pixel = gain * rc.c[ch];
    const bool in_range = pixel >= 0.f && pixel <= 1.f;
    const float cc = std::min(std::max(pixel, 0.f), 1.f);
    const float diff = cc - loss.target_rgb[3 * r + ch];
    sse += static_cast<double>(diff) * diff;
    const float g_pixel = in_range ? loss.grad_scale * diff : 0.f;
    if (loss.dl_dgain) loss.dl_dgain[3 * r + ch] = g_pixel * rc.c[ch];
    g[ch] = g_pixel * gain;
  }
}

// Compositing backward of one ray, from its last sample to its first (the suffix sums of the
// weights' gradients): each sample's feat becomes dL/dfeature. colour(sample, w) returns the
// coloured sample's dL/dw through its colour and writes what its head needs. Returns the ray's
// distortion loss.
template <class ColourTerm>
inline double CompositeBackward(const RayLoss& loss, SampleRec* s, int count,
                                const RayComposite& rc, const float g[3], ColourTerm colour) {
  const float bg_dot = loss.white ? g[0] + g[1] + g[2] : 0.f;
  float suffix = 0.f;
  double w_after = 0.0, wm_after = 0.0, ray_distortion = 0.0;
  for (int k = count - 1; k >= 0; --k) {
    SampleRec& sk = s[k];
    const float w = sk.alpha * sk.trans;
    float e = -bg_dot;
    if (loss.distortion_on) {
      const double inv_n = loss.inv_n;
      const double m = sk.s * inv_n, wk = w;
      const double w_before = rc.w_total - w_after - wk;
      const double wm_before = rc.wm_total - wm_after - wk * m;
      const double spread = (m * w_before - wm_before) + (wm_after - m * w_after);
      ray_distortion += wk * spread + inv_n / 3.0 * wk * wk;
      e += static_cast<float>(loss.distortion_scale * (2.0 * spread + 2.0 * inv_n / 3.0 * wk));
      w_after += wk;
      wm_after += wk * m;
    }
    if (sk.app >= 0) e += colour(sk, w);
    const float f = (1.f - sk.alpha) + 1e-10f;
    const float dl_dalpha = e * sk.trans - suffix / f;
    suffix += e * w;
    const float dl_dsigma = dl_dalpha * (1.f - sk.alpha) * sk.dscale;
    sk.feat = dl_dsigma * DensityActivationGrad(loss.activation, sk.feat);
  }
  return ray_distortion;
}

// The rays [r0, r1) of a chunk and its rows of appearance samples, [base, base + rows).
struct RayChunk {
  int r0, r1;
  int64_t base, rows;
};

// The chunk from ray r0: the most consecutive rays (at least one) whose appearance samples fit in
// max_rows rows.
inline RayChunk NextChunk(const Workspace& ws, int r0, int n_rays, int64_t max_rows) {
  int r1 = r0 + 1;
  while (r1 < n_rays &&
         ws.rays[r1].app_start + ws.rays[r1].app_count - ws.rays[r0].app_start <= max_rows)
    ++r1;
  const int64_t base = ws.rays[r0].app_start;
  return {r0, r1, base, ws.rays[r1 - 1].app_start + ws.rays[r1 - 1].app_count - base};
}

// The deferred head's inputs (SPEC.md 7.6) for rays [r0, r1), whose samples' products are rows
// app_start - base + app of ws.products: a row per ray with a coloured sample (ws.head_rays), the
// sum of those samples' products weighted by their weights, and the ray's view direction.
// Returns the number of rows.
int SumRayProducts(Workspace& ws, int r0, int r1, int64_t base, int P, const float* dirs);

// The deferred head's part of a step for one chunk (the per-sample head's is in TrainStep): the
// summed products, the head forward, compositing and loss, the head backward and the compositing
// backward. The scatter then takes each sample's products gradient from its ray's (ScatterChunk);
// lap() times the phases.
void DeferredChunk(const RayLoss& loss, AppearanceHead& head, Workspace& ws, const RayChunk& chunk,
                   int P, const float* dirs, TrainStepStats& stats,
                   const std::function<double()>& lap, double& sse, long& n_density,
                   double& distortion_sum);

}  // namespace batch
}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_MODEL_RAY_BATCH_H_
