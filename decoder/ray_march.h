// Internal to the renderer (decoder/ray_marcher.cc, decoder/ray_march.cc): the per-thread
// workspace, the job a render hands its threads, the per-render constants, and the marching of
// one tile of rays (SPEC.md 7.2-7.5) with its work accounting (decoder/render_work.h).
#ifndef ECRF_DECODER_RAY_MARCH_H_
#define ECRF_DECODER_RAY_MARCH_H_

#include <atomic>
#include <cstddef>
#include <cstdint>

#include "decoder/camera.h"
#include "decoder/field.h"
#include "decoder/grid_point.h"
#include "decoder/ray_marcher.h"
#include "decoder/render_work.h"

namespace ecrf {
namespace dec {

struct BatchEntry {
  int slot;
  float weight;
  GridPoint gp;
};

struct RayMarcher::Workspace {
  HeapArray<BatchEntry> entries;  // batch_rows
  HeapArray<float> products;      // batch_rows x pstride
  HeapArray<float> viewdirs;      // batch_rows x 3
  HeapArray<float> colors;        // batch_rows x 3
  HeapArray<float> mlp_scratch;
  HeapArray<float> ray_o, ray_d, ray_rgb, ray_acc;  // tile rays
  // Deferred head (SPEC.md 7.6): per tile ray the weighted sum of its coloured samples' products
  // (tile rays x pstride) and of their weights.
  HeapArray<float> ray_products, ray_color_weight;
  size_t pstride = 1;
  int capacity = 0;
  int count = 0;
  RenderStats stats;
  // Work budget (render_work.h): this thread's unspent share, refilled from the view's pool.
  int64_t credit = 0;
  std::atomic<int64_t>* pool = nullptr;
  std::atomic<bool>* exhausted = nullptr;
};

struct RayMarcher::Job {
  bool image = false;
  const Camera* camera = nullptr;
  uint8_t* rgba8 = nullptr;
  float* image_rgb = nullptr;
  int tiles_x = 0;
  size_t count = 0;
  const float* origins = nullptr;
  const float* dirs = nullptr;
  float* rgb = nullptr;
  float* acc = nullptr;
  size_t num_tiles = 0;
  std::atomic<size_t> next{0};
  std::atomic<int64_t> work_left{0};  // the view's work budget not yet handed to a thread
  std::atomic<bool> exhausted{false};
};

// Per-render constants.
struct Ctx {
  const SceneField* s;
  float min[3], max[3], inv[3];  // inv = 2 / (max - min), as TensoRF's invaabbSize
  float step;
  double inv_step;  // 1 / step: a positive float's reciprocal is finite and normal in double
  int n;
  float near, far;
  DensityActivation activation;
  float shift, dscale, wthr, early;
  const OccupancyMask* mask;  // null: no mask
  bool skip;
  bool unbounded;                  // SPEC.md 7.2.1; min/max/inv then span the contracted cube
  bool forward;                    // SPEC.md 7.2.2; min/max/inv are in NDC
  bool deferred;                   // the deferred head: products composited, MLP once per ray
  float roi_min[3], roi_scale[3];  // unbounded: the HEAD box, (1 / (max - min)) * 2
  double mask_scale[3];            // (res - 1) / (max - min) of the mask
  int tile_size;
  int tile_rays;
  SampleCosts cost;
};

// Clip3(0, 1, v) of SPEC.md 7.2, with NaN (from a stream whose weights or steps overflow in the
// arithmetic) mapped to 0 like a negative value: every output is a number in [0, 1].
inline float ClipUnit(float v) { return v > 0.f ? (v < 1.f ? v : 1.f) : 0.f; }

// Marches ws.ray_o/ray_d[0..nrays) and leaves the final clamped colour in ws.ray_rgb; the
// accumulated opacity in ws.ray_acc. Rays are skipped once the view has spent its work budget.
void ProcessRays(const Ctx& c, RayMarcher::Workspace& ws, int nrays);

}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_DECODER_RAY_MARCH_H_
