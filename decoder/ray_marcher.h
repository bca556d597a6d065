// RayMarcher: renders a SceneField with TensoRF's inference ray marching (sample_ray with
// is_train=False, raw2alpha, weight threshold, white/any background).
//
// Per ray: vec = d with zero components replaced by 1e-6, t_min = clamp(max_a min((max-o)/vec,
// (min-o)/vec), near, far), samples t_i = t_min + i*step (i < n_samples), points outside the aabb
// or with alpha-mask value 0 get sigma 0, dist_i = t_{i+1} - t_i (0 for the last sample),
// alpha = 1 - exp(-sigma * dist * distance_scale), weight = alpha * T, T *= 1 - alpha + 1e-10;
// colour (MLP) only where weight > weight_threshold; rgb = sum weight*rgb + (1 - acc) * background,
// clamped to [0,1]. Sample positions are computed in float exactly as the reference does.
//
// Empty-space skipping (option) walks a max-pooled hierarchy of the alpha mask (16^3 and 4^3
// cells) and jumps over every sample inside an empty block; margins make it skip only samples
// whose mask value is provably 0, so the image is bit-identical to marching without skipping.
// Samples before the box entry / after the exit are skipped analytically the same way.
//
// Appearance samples of a tile of rays are batched through the MLP; with the deferred head
// (SPEC.md 7.6.1) each ray sums its coloured samples' weighted products instead, and the tile's
// rays with a coloured sample go through the MLP once each. Threads (std::thread) take
// tiles from a shared counter; each ray's arithmetic is independent of the tile / batch / thread it
// runs in, so the output does not depend on the thread count. Nothing is allocated while
// rendering: Init allocates the per-thread workspaces.
#ifndef ECRF_DECODER_RAY_MARCHER_H_
#define ECRF_DECODER_RAY_MARCHER_H_

#include <cstddef>
#include <cstdint>

#include "decoder/camera.h"
#include "decoder/field.h"
#include "decoder/render_work.h"
#include "ecrf/decoder.h"
#include "format/status.h"

namespace ecrf {
namespace dec {

inline constexpr int kMaxRenderThreads = 64;
inline constexpr int64_t kMaxImagePixels = int64_t{1} << 26;
inline constexpr float kMinStepScale = 1.f / 16, kMaxStepScale = 64.f;
// Default RenderOptions::sample_budget: 16x the samples of a 400x400 Synthetic-NeRF scene.
inline constexpr int kDefaultSampleBudget = ECRF_DEFAULT_SAMPLE_BUDGET;

struct RenderOptions {
  int num_threads = 1;  // 0: std::thread::hardware_concurrency(); 1: no thread is created
  int max_samples = 0;  // cap on samples per ray (0: the scene's n_samples)
  bool skip_empty_space = true;
  // Stop a ray once T < this (0: off, the reference). Samples past that point have weight <= T,
  // so with a value <= weight_threshold only acc changes, by < this value.
  float early_stop_transmittance = 1e-4f;
  // Speed knobs that leave the reference process (SPEC.md 7.8). step_scale multiplies the
  // distance between samples and divides their number (rounded up), so a ray covers the same
  // length with fewer samples; 1 is the reference.
  float step_scale = 1.f;
  // Colour only samples whose weight exceeds this; negative: the scene's weight_threshold.
  float weight_threshold = -1.f;
  // Init refuses (kErrLimit) a scene whose rays would take more samples than this after
  // step_scale and max_samples (0: no limit). The format allows 2^20 samples per ray, which makes a
  // 32x32 view of a few-hundred-byte stream take half a minute; the default keeps that cheap.
  int sample_budget = kDefaultSampleBudget;
  // Multiply-adds a view may spend per pixel on average (decoder/render_work.h; 0: no limit).
  // Init refuses a scene one colour sample of which costs more; a render that spends
  // pixels x work_budget stops and returns kErrLimit.
  uint64_t work_budget = kDefaultWorkBudget;
  int tile_size = 8;     // image tiles are tile_size^2 pixels; RenderRays uses tile_size^2 rays
  int batch_rows = 256;  // appearance samples per MLP batch
};

struct RenderStats {
  uint64_t rays = 0;
  uint64_t samples = 0;        // samples whose density was evaluated (inside aabb and mask)
  uint64_t color_samples = 0;  // samples that went through the MLP
  uint64_t work = 0;           // multiply-adds charged to the work budget (render_work.h)
  void Add(const RenderStats& o) {
    rays += o.rays;
    work += o.work;
    samples += o.samples;
    color_samples += o.color_samples;
  }
};

class RayMarcher {
 public:
  RayMarcher();
  ~RayMarcher();
  RayMarcher(const RayMarcher&) = delete;
  RayMarcher& operator=(const RayMarcher&) = delete;

  // Validates the scene and options and allocates per-thread workspaces. `scene` must stay alive
  // and unchanged while this marcher renders it. Not thread-safe: one render call at a time.
  Status Init(const SceneField* scene, const RenderOptions& options);

  // rgba8: width*height*4 bytes (alpha = accumulated opacity) and/or rgb: width*height*3 floats,
  // row-major from the top row; either may be null (not both).
  Status RenderImage(const Camera& camera, uint8_t* rgba8, float* rgb,
                     RenderStats* stats = nullptr);

  // count rays: origins / dirs count x 3 (dirs used as given for sampling and as viewdirs; pass
  // unit vectors as TensoRF does). rgb: count x 3, acc (optional): count.
  Status RenderRays(size_t count, const float* origins, const float* dirs, float* rgb, float* acc,
                    RenderStats* stats = nullptr);

  // One work budget for a view rendered in several RenderRays calls (a caller that renders a
  // large image a band of rows at a time): view_pixels x work_budget, spent by every call until
  // EndView, and the refusal names the view's pixels. Without it each call has its own budget of
  // count x work_budget. Init ends a view.
  void BeginView(uint64_t view_pixels);
  void EndView() { view_ = false; }

  // Internal (defined in ray_marcher.cc).
  struct Workspace;
  struct Job;

 private:
  Status Run(Job* job, uint64_t pixels, RenderStats* stats);

  const SceneField* scene_ = nullptr;
  RenderOptions options_;
  int threads_ = 1;
  SampleCosts costs_;
  Workspace* workspaces_ = nullptr;  // threads_ of them
  bool view_ = false;                // between BeginView and EndView
  uint64_t view_pixels_ = 0;
  int64_t view_left_ = 0;  // the view's unspent budget (below 0 once spent)
};

}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_DECODER_RAY_MARCHER_H_
