#include "decoder/ray_marcher.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <new>
#include <thread>

#include "decoder/contraction.h"
#include "decoder/field_sampler.h"
#include "decoder/ndc.h"

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
  size_t pstride = 1;
  int capacity = 0;
  int count = 0;
  RenderStats stats;
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
};

namespace {

// Per-render constants.
struct Ctx {
  const SceneField* s;
  float min[3], max[3], inv[3];  // inv = 2 / (max - min), as TensoRF's invaabbSize
  float step;
  int n;
  float near, far;
  float shift, dscale, wthr, early;
  const OccupancyMask* mask;  // null: no mask
  bool skip;
  bool unbounded;                  // SPEC.md 7.2.1; min/max/inv then span the contracted cube
  bool forward;                    // SPEC.md 7.2.2; min/max/inv are in NDC
  float roi_min[3], roi_scale[3];  // unbounded: the HEAD box, (1 / (max - min)) * 2
  double mask_scale[3];            // (res - 1) / (max - min) of the mask
  int tile_size;
  int tile_rays;
};

inline float SampleT(float t0, float step, int i) { return t0 + step * static_cast<float>(i); }

// Smallest j in [0, n] with SampleT(j) >= lim (SampleT is non-decreasing in j).
int FirstIndexAtLeast(float t0, float step, int n, double lim) {
  const double est = std::ceil((lim - t0) / step);
  int j = !(est > 0.0) ? 0 : (est >= n ? n : static_cast<int>(est));
  while (j > 0 && static_cast<double>(SampleT(t0, step, j - 1)) >= lim) --j;
  while (j < n && static_cast<double>(SampleT(t0, step, j)) < lim) ++j;
  return j;
}

// Largest j in [i - 1, n - 1] with SampleT(j) <= lim.
int LastIndexAtMost(float t0, float step, int n, int i, double lim) {
  const double est = std::floor((lim - t0) / step);
  int j = !(est > i - 1) ? i - 1 : (est >= n - 1 ? n - 1 : static_cast<int>(est));
  while (j + 1 < n && static_cast<double>(SampleT(t0, step, j + 1)) <= lim) ++j;
  while (j >= i && static_cast<double>(SampleT(t0, step, j)) > lim) --j;
  return j;
}

// Sample i (mask index idx) lies in an empty block: returns the first sample index past the run of
// samples that provably stay inside that block (i itself when that cannot be proven).
int SkipEmpty(const Ctx& c, const float o[3], const float d[3], float t0, int i, double tspan,
              const float idx[3]) {
  const OccupancyMask& mask = *c.mask;
  const int* res = mask.res();
  for (int a = 0; a < 3; ++a) {
    if (!(idx[a] >= 0.f && idx[a] <= static_cast<float>(res[a] - 1))) return i;
  }
  for (int level = 0; level < OccupancyMask::kLevels; ++level) {
    int lo[3], hi[3];
    if (!mask.EmptyBlock(level, idx, lo, hi)) continue;
    // t-range where the exact position o + d t stays within [lo + m, hi - m] per axis; m covers
    // the float rounding of the reference's index computation.
    double tlo = -INFINITY, thi = INFINITY;
    for (int a = 0; a < 3; ++a) {
      if (d[a] == 0.f) continue;  // constant float index, already inside [lo, hi]
      const double S = c.mask_scale[a];
      const double A = (static_cast<double>(o[a]) - mask.aabb_min()[a]) * S;
      const double D = static_cast<double>(d[a]) * S;
      const double m = 1e-4 + 2e-6 * res[a] +
                       1e-6 *
                           (std::fabs(o[a]) + std::fabs(d[a]) * tspan +
                            std::fabs(mask.aabb_min()[a]) + std::fabs(mask.aabb_max()[a])) *
                           S;
      double ta = (lo[a] + m - A) / D, tb = (hi[a] - m - A) / D;
      if (ta > tb) std::swap(ta, tb);
      tlo = std::max(tlo, ta);
      thi = std::min(thi, tb);
    }
    if (!(static_cast<double>(SampleT(t0, c.step, i)) >= tlo)) return i;
    const int j = LastIndexAtMost(t0, c.step, c.n, i, thi);
    return j >= i ? j + 1 : i;
  }
  return i;
}

void Flush(const Ctx& c, RayMarcher::Workspace& ws) {
  const int n = ws.count;
  if (n == 0) return;
  const VmGrid& app = c.s->appearance;
  for (int e = 0; e < n; ++e) {
    const BatchEntry& be = ws.entries[e];
    AppearanceProducts(app, be.gp, ws.products.data() + static_cast<size_t>(e) * ws.pstride);
    const float* d = ws.ray_d.data() + static_cast<size_t>(be.slot) * 3;
    float* vd = ws.viewdirs.data() + static_cast<size_t>(e) * 3;
    vd[0] = d[0];
    vd[1] = d[1];
    vd[2] = d[2];
  }
  c.s->mlp.Infer(n, ws.products.data(), ws.pstride, ws.viewdirs.data(), ws.colors.data(),
                 ws.mlp_scratch.data());
  for (int e = 0; e < n; ++e) {
    const BatchEntry& be = ws.entries[e];
    float* rgb = ws.ray_rgb.data() + static_cast<size_t>(be.slot) * 3;
    const float* col = ws.colors.data() + static_cast<size_t>(e) * 3;
    rgb[0] += be.weight * col[0];
    rgb[1] += be.weight * col[1];
    rgb[2] += be.weight * col[2];
  }
  ws.stats.color_samples += static_cast<uint64_t>(n);
  ws.count = 0;
}

// Evaluates the sample at grid-box point p (world for the object model, contracted for the
// unbounded one) with interval `dist` and composites it (7.2, 7.5). False once the ray may stop
// early (T below the early-termination threshold).
bool CompositeSample(const Ctx& c, RayMarcher::Workspace& ws, int slot, const float p[3],
                     float dist, float* T, float* acc) {
  ++ws.stats.samples;
  float cn[3];
  for (int a = 0; a < 3; ++a) cn[a] = (p[a] - c.min[a]) * c.inv[a] - 1.f;
  GridPoint gp;
  LocateGridPoint(cn, c.s->res, &gp);
  const float sigma = Softplus(DensityFeature(c.s->density, gp) + c.shift);
  const float alpha = 1.f - std::exp(-sigma * (dist * c.dscale));
  const float weight = alpha * *T;
  *T *= 1.f - alpha + 1e-10f;
  *acc += weight;
  if (weight > c.wthr) {
    BatchEntry& be = ws.entries[ws.count++];
    be.slot = slot;
    be.weight = weight;
    be.gp = gp;
    if (ws.count == ws.capacity) Flush(c, ws);
  }
  return !(*T < c.early);
}

// SPEC.md 7.2: the straight line o + d t through the box (world for the object model, NDC for
// the forward-facing one); the colour samples take their view direction from ws.ray_d[slot].
void MarchStraight(const Ctx& c, RayMarcher::Workspace& ws, int slot, const float* o,
                   const float* d) {
  ws.ray_acc[slot] = 0.f;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(o[a]) || !std::isfinite(d[a])) return;
  }
  // Reference t_min (sample_ray): zero components replaced by 1e-6, clamped to [near, far].
  float tmin = -INFINITY;
  for (int a = 0; a < 3; ++a) {
    const float vec = d[a] == 0.f ? 1e-6f : d[a];
    const float ra = (c.max[a] - o[a]) / vec;
    const float rb = (c.min[a] - o[a]) / vec;
    tmin = std::max(tmin, std::min(ra, rb));
  }
  const float t0 = std::min(std::max(tmin, c.near), c.far);
  const int n = c.n;
  const float step = c.step;
  // Exact slab of the sampled line o + d t, widened by a bound on the float error of the sample
  // positions: samples outside [te, tx] are certainly outside the box.
  const double tspan = std::fabs(static_cast<double>(t0)) + static_cast<double>(step) * n;
  double te = -INFINITY, tx = INFINITY;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.f) {
      if (o[a] < c.min[a] || o[a] > c.max[a]) return;  // p[a] == o[a] for every sample
      continue;
    }
    double t1 = (static_cast<double>(c.min[a]) - o[a]) / d[a];
    double t2 = (static_cast<double>(c.max[a]) - o[a]) / d[a];
    if (t1 > t2) std::swap(t1, t2);
    const double err =
        1e-6 *
        (std::fabs(o[a]) + std::fabs(d[a]) * tspan + std::fabs(c.min[a]) + std::fabs(c.max[a])) /
        std::fabs(d[a]);
    te = std::max(te, t1 - err);
    tx = std::min(tx, t2 + err);
  }
  if (te > tx) return;

  float T = 1.f, acc = 0.f;
  int i = FirstIndexAtLeast(t0, step, n, te);
  while (i < n) {
    const float t = SampleT(t0, step, i);
    if (static_cast<double>(t) > tx) break;
    const float p[3] = {o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t};
    if (c.min[0] > p[0] || p[0] > c.max[0] || c.min[1] > p[1] || p[1] > c.max[1] ||
        c.min[2] > p[2] || p[2] > c.max[2]) {
      ++i;
      continue;
    }
    if (c.mask != nullptr) {
      float idx[3];
      c.mask->Index(p, idx);
      if (c.skip) {
        const int j = SkipEmpty(c, o, d, t0, i, tspan, idx);
        if (j > i) {
          i = j;
          continue;
        }
      }
      if (!c.mask->OccupiedAtIndex(idx)) {
        ++i;
        continue;
      }
    }
    const float dist = i + 1 < n ? SampleT(t0, step, i + 1) - t : 0.f;
    if (!CompositeSample(c, ws, slot, p, dist, &T, &acc)) break;
    ++i;
  }
  ws.ray_acc[slot] = acc;
}

void MarchRay(const Ctx& c, RayMarcher::Workspace& ws, int slot) {
  MarchStraight(c, ws, slot, ws.ray_o.data() + static_cast<size_t>(slot) * 3,
                ws.ray_d.data() + static_cast<size_t>(slot) * 3);
}

// SPEC.md 7.2.2: the object process along the ray's image in NDC; the MLP sees the world direction.
void MarchRayForward(const Ctx& c, RayMarcher::Workspace& ws, int slot) {
  const float* o = ws.ray_o.data() + static_cast<size_t>(slot) * 3;
  const float* d = ws.ray_d.data() + static_cast<size_t>(slot) * 3;
  ws.ray_acc[slot] = 0.f;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(o[a]) || !std::isfinite(d[a])) return;
  }
  float ndc_o[3], ndc_d[3];
  if (!NdcRay(c.s->ndc, o, d, ndc_o, ndc_d)) return;
  MarchStraight(c, ws, slot, ndc_o, ndc_d);
}

// SPEC.md 7.2.1: samples from `near` on, spaced `step` apart in contracted distance, until the
// sample budget or the edge of the contracted cube. The mask hierarchy assumes straight rays, so
// empty space is skipped only sample by sample here (the output is the same).
void MarchRayUnbounded(const Ctx& c, RayMarcher::Workspace& ws, int slot) {
  const ContractedRay ray(ws.ray_o.data() + static_cast<size_t>(slot) * 3,
                          ws.ray_d.data() + static_cast<size_t>(slot) * 3, c.roi_min, c.roi_scale,
                          c.step);
  ws.ray_acc[slot] = 0.f;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(ray.o[a]) || !std::isfinite(ray.d[a])) return;
  }
  float T = 1.f, acc = 0.f;
  float t = c.near;
  for (int i = 0; i < c.n; ++i) {
    float q[3], x[3];
    ray.At(t, q, x);
    const float next = t + ray.Increment(q);
    const bool last = i + 1 == c.n || !std::isfinite(next);
    const float dist = last ? 0.f : next - t;
    bool occupied = true;
    if (c.mask != nullptr) {
      float idx[3];
      c.mask->Index(x, idx);
      occupied = c.mask->OccupiedAtIndex(idx);
    }
    if (occupied && !CompositeSample(c, ws, slot, x, dist, &T, &acc)) break;
    if (last) break;
    t = next;
  }
  ws.ray_acc[slot] = acc;
}

// Clip3(0, 1, v) of SPEC.md 7.2, with NaN (from a stream whose weights or steps overflow in the
// arithmetic) mapped to 0 like a negative value: every output is a number in [0, 1].
inline float ClipUnit(float v) { return v > 0.f ? (v < 1.f ? v : 1.f) : 0.f; }

// Marches ws.ray_o/ray_d[0..nrays) and leaves the final clamped colour in ws.ray_rgb.
void ProcessRays(const Ctx& c, RayMarcher::Workspace& ws, int nrays) {
  std::memset(ws.ray_rgb.data(), 0, static_cast<size_t>(nrays) * 3 * sizeof(float));
  ws.count = 0;
  for (int r = 0; r < nrays; ++r) {
    if (c.unbounded) {
      MarchRayUnbounded(c, ws, r);
    } else if (c.forward) {
      MarchRayForward(c, ws, r);
    } else {
      MarchRay(c, ws, r);
    }
  }
  Flush(c, ws);
  const float* bg = c.s->background;
  for (int r = 0; r < nrays; ++r) {
    float* rgb = ws.ray_rgb.data() + static_cast<size_t>(r) * 3;
    const float rest = 1.f - ws.ray_acc[r];
    for (int k = 0; k < 3; ++k) {
      const float v = rgb[k] + rest * bg[k];
      rgb[k] = ClipUnit(v);
    }
  }
  ws.stats.rays += static_cast<uint64_t>(nrays);
}

uint8_t ToByte(float v) { return static_cast<uint8_t>(ClipUnit(v) * 255.f + 0.5f); }

}  // namespace

// Samples per ray after the speed knobs of SPEC.md 7.8: ceil(n / step_scale) in float64, then
// the max_samples cap. Init checks it against the sample budget; Run marches that many.
namespace {
int SamplesPerRay(const SceneField& s, const RenderOptions& options) {
  int n = s.NumSamples();
  if (options.step_scale != 1.f) {
    const double scaled =
        std::ceil(static_cast<double>(n) / static_cast<double>(options.step_scale));
    n = scaled >= 1e9 ? 1000000000 : static_cast<int>(scaled);
  }
  if (options.max_samples > 0 && options.max_samples < n) n = options.max_samples;
  return n;
}
}  // namespace

RayMarcher::RayMarcher() = default;
RayMarcher::~RayMarcher() { delete[] workspaces_; }

Status RayMarcher::Init(const SceneField* scene, const RenderOptions& options) {
  delete[] workspaces_;
  workspaces_ = nullptr;
  scene_ = nullptr;
  ECRF_CHECK_OR_RETURN(scene != nullptr, kErrInvalidArgument, "render: null scene");
  ECRF_RETURN_IF_ERROR(scene->Validate());
  ECRF_CHECK_OR_RETURN(options.num_threads >= 0 && options.num_threads <= kMaxRenderThreads,
                       kErrInvalidArgument, "render: num_threads %d out of range [0, %d]",
                       options.num_threads, kMaxRenderThreads);
  ECRF_CHECK_OR_RETURN(options.tile_size >= 1 && options.tile_size <= 64, kErrInvalidArgument,
                       "render: tile_size %d out of range [1, 64]", options.tile_size);
  ECRF_CHECK_OR_RETURN(options.batch_rows >= 1 && options.batch_rows <= 65536, kErrInvalidArgument,
                       "render: batch_rows %d out of range [1, 65536]", options.batch_rows);
  ECRF_CHECK_OR_RETURN(options.max_samples >= 0, kErrInvalidArgument,
                       "render: negative max_samples");
  ECRF_CHECK_OR_RETURN(
      options.early_stop_transmittance >= 0.f && options.early_stop_transmittance <= 1.f,
      kErrInvalidArgument, "render: early_stop_transmittance not in [0, 1]");
  ECRF_CHECK_OR_RETURN(options.step_scale >= kMinStepScale && options.step_scale <= kMaxStepScale,
                       kErrInvalidArgument, "render: step_scale %g not in [1/16, 64]",
                       static_cast<double>(options.step_scale));
  ECRF_CHECK_OR_RETURN(!(options.weight_threshold > 1.f) && !std::isnan(options.weight_threshold),
                       kErrInvalidArgument, "render: weight_threshold %g above 1",
                       static_cast<double>(options.weight_threshold));
  ECRF_CHECK_OR_RETURN(options.sample_budget >= 0, kErrInvalidArgument,
                       "render: negative sample_budget");
  if (options.sample_budget > 0) {
    const int n = SamplesPerRay(*scene, options);
    ECRF_CHECK_OR_RETURN(
        n <= options.sample_budget, kErrLimit,
        "render: the scene asks %d samples per ray, more than the sample budget of %d "
        "(RenderOptions::sample_budget; ecrf --sample-budget N, or cap with --samples N)",
        n, options.sample_budget);
  }
  int threads = options.num_threads;
  if (threads == 0) {
    const unsigned hw = std::thread::hardware_concurrency();
    threads = hw == 0 ? 1
                      : (hw > static_cast<unsigned>(kMaxRenderThreads) ? kMaxRenderThreads
                                                                       : static_cast<int>(hw));
  }
  workspaces_ = new (std::nothrow) Workspace[threads];
  ECRF_CHECK_OR_RETURN(workspaces_ != nullptr, kErrOutOfMemory, "render: out of memory");
  const int tile_rays = options.tile_size * options.tile_size;
  const size_t P = static_cast<size_t>(scene->appearance.total_rank());
  const size_t pstride = P == 0 ? 1 : (P + 7) / 8 * 8;
  for (int t = 0; t < threads; ++t) {
    Workspace& ws = workspaces_[t];
    size_t prod = 0;
    ECRF_CHECK_OR_RETURN(CheckedMul(pstride, static_cast<size_t>(options.batch_rows), &prod),
                         kErrLimit, "render: batch too large");
    ECRF_RETURN_IF_ERROR(ws.entries.Allocate(options.batch_rows));
    ECRF_RETURN_IF_ERROR(ws.products.Allocate(prod));
    ECRF_RETURN_IF_ERROR(ws.viewdirs.Allocate(static_cast<size_t>(options.batch_rows) * 3));
    ECRF_RETURN_IF_ERROR(ws.colors.Allocate(static_cast<size_t>(options.batch_rows) * 3));
    ECRF_RETURN_IF_ERROR(ws.mlp_scratch.Allocate(scene->mlp.ScratchFloats()));
    ECRF_RETURN_IF_ERROR(ws.ray_o.Allocate(static_cast<size_t>(tile_rays) * 3));
    ECRF_RETURN_IF_ERROR(ws.ray_d.Allocate(static_cast<size_t>(tile_rays) * 3));
    ECRF_RETURN_IF_ERROR(ws.ray_rgb.Allocate(static_cast<size_t>(tile_rays) * 3));
    ECRF_RETURN_IF_ERROR(ws.ray_acc.Allocate(static_cast<size_t>(tile_rays)));
    ws.pstride = pstride;
    ws.capacity = options.batch_rows;
  }
  scene_ = scene;
  options_ = options;
  threads_ = threads;
  return Status::Ok();
}

namespace {

void Worker(const Ctx& c, RayMarcher::Job* job, RayMarcher::Workspace* ws);

}  // namespace

Status RayMarcher::Run(Job* job, RenderStats* stats) {
  const SceneField& s = *scene_;
  Ctx c;
  c.s = &s;
  c.unbounded = s.scene_model == SceneModel::kUnbounded;
  c.forward = s.scene_model == SceneModel::kForward;
  for (int a = 0; a < 3; ++a) {
    c.roi_min[a] = s.aabb_min[a];
    c.roi_scale[a] = 1.0f / (s.aabb_max[a] - s.aabb_min[a]) * 2.f;
    c.min[a] = c.unbounded ? -kContractedExtent : s.aabb_min[a];
    c.max[a] = c.unbounded ? kContractedExtent : s.aabb_max[a];
    c.inv[a] = 1.0f / (c.max[a] - c.min[a]) * 2.f;
  }
  c.step = s.StepSize();
  if (options_.step_scale != 1.f) c.step *= options_.step_scale;
  c.n = SamplesPerRay(s, options_);
  c.near = s.near_far[0];
  c.far = s.near_far[1];
  c.shift = s.density_shift;
  c.dscale = s.distance_scale;
  c.wthr = options_.weight_threshold >= 0.f ? options_.weight_threshold : s.weight_threshold;
  c.early = options_.early_stop_transmittance;
  c.mask = s.has_mask ? &s.mask : nullptr;
  ECRF_CHECK_OR_RETURN(c.mask == nullptr || c.mask->acceleration_ready(), kErrInvalidArgument,
                       "render: alpha mask acceleration not built");
  c.skip = options_.skip_empty_space && c.mask != nullptr && !c.unbounded;
  for (int a = 0; a < 3; ++a) {
    c.mask_scale[a] =
        c.mask == nullptr
            ? 0.0
            : static_cast<double>(c.mask->res()[a] - 1) /
                  (static_cast<double>(c.mask->aabb_max()[a]) - c.mask->aabb_min()[a]);
  }
  c.tile_size = options_.tile_size;
  c.tile_rays = options_.tile_size * options_.tile_size;

  for (int t = 0; t < threads_; ++t) workspaces_[t].stats = RenderStats();
  const int nthreads =
      static_cast<size_t>(threads_) < job->num_tiles ? threads_ : static_cast<int>(job->num_tiles);
  if (nthreads <= 1) {
    Worker(c, job, &workspaces_[0]);
  } else {
    std::thread pool[kMaxRenderThreads];
    for (int t = 1; t < nthreads; ++t)
      pool[t] = std::thread(Worker, std::cref(c), job, &workspaces_[t]);
    Worker(c, job, &workspaces_[0]);
    for (int t = 1; t < nthreads; ++t) pool[t].join();
  }
  if (stats != nullptr) {
    *stats = RenderStats();
    for (int t = 0; t < threads_; ++t) stats->Add(workspaces_[t].stats);
  }
  return Status::Ok();
}

namespace {

void Worker(const Ctx& c, RayMarcher::Job* job, RayMarcher::Workspace* ws) {
  for (;;) {
    const size_t tile = job->next.fetch_add(1, std::memory_order_relaxed);
    if (tile >= job->num_tiles) break;
    if (job->image) {
      const Camera& cam = *job->camera;
      const int x0 = static_cast<int>(tile % job->tiles_x) * c.tile_size;
      const int y0 = static_cast<int>(tile / job->tiles_x) * c.tile_size;
      const int x1 = std::min(x0 + c.tile_size, cam.width);
      const int y1 = std::min(y0 + c.tile_size, cam.height);
      int r = 0;
      for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; ++x, ++r) {
          CameraRay(cam, x, y, ws->ray_o.data() + 3 * r, ws->ray_d.data() + 3 * r);
        }
      }
      ProcessRays(c, *ws, r);
      r = 0;
      for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; ++x, ++r) {
          const size_t px = static_cast<size_t>(y) * cam.width + x;
          const float* rgb = ws->ray_rgb.data() + 3 * r;
          if (job->image_rgb != nullptr)
            std::memcpy(job->image_rgb + 3 * px, rgb, 3 * sizeof(float));
          if (job->rgba8 != nullptr) {
            uint8_t* q = job->rgba8 + 4 * px;
            q[0] = ToByte(rgb[0]);
            q[1] = ToByte(rgb[1]);
            q[2] = ToByte(rgb[2]);
            q[3] = ToByte(ws->ray_acc[r]);
          }
        }
      }
    } else {
      const size_t first = tile * static_cast<size_t>(c.tile_rays);
      const int nr =
          static_cast<int>(std::min(static_cast<size_t>(c.tile_rays), job->count - first));
      std::memcpy(ws->ray_o.data(), job->origins + 3 * first,
                  static_cast<size_t>(nr) * 3 * sizeof(float));
      std::memcpy(ws->ray_d.data(), job->dirs + 3 * first,
                  static_cast<size_t>(nr) * 3 * sizeof(float));
      ProcessRays(c, *ws, nr);
      std::memcpy(job->rgb + 3 * first, ws->ray_rgb.data(),
                  static_cast<size_t>(nr) * 3 * sizeof(float));
      if (job->acc != nullptr) {
        for (int r = 0; r < nr; ++r) {
          const float a = ws->ray_acc[r];
          job->acc[first + r] = a;
        }
      }
    }
  }
}

}  // namespace

Status RayMarcher::RenderImage(const Camera& camera, uint8_t* rgba8, float* rgb,
                               RenderStats* stats) {
  ECRF_CHECK_OR_RETURN(scene_ != nullptr, kErrInvalidArgument, "render: Init first");
  ECRF_CHECK_OR_RETURN(rgba8 != nullptr || rgb != nullptr, kErrInvalidArgument,
                       "render: no output buffer");
  ECRF_CHECK_OR_RETURN(camera.width > 0 && camera.height > 0 &&
                           static_cast<int64_t>(camera.width) * camera.height <= kMaxImagePixels,
                       kErrLimit, "render: image size %dx%d out of range", camera.width,
                       camera.height);
  bool finite = std::isfinite(camera.fx) && std::isfinite(camera.fy) && camera.fx != 0.f &&
                camera.fy != 0.f && std::isfinite(camera.cx) && std::isfinite(camera.cy);
  for (float v : camera.c2w) finite = finite && std::isfinite(v);
  ECRF_CHECK_OR_RETURN(finite, kErrInvalidArgument, "render: non-finite or degenerate camera");
  Job job;
  job.image = true;
  job.camera = &camera;
  job.rgba8 = rgba8;
  job.image_rgb = rgb;
  const int ts = options_.tile_size;
  job.tiles_x = (camera.width + ts - 1) / ts;
  job.num_tiles = static_cast<size_t>(job.tiles_x) * ((camera.height + ts - 1) / ts);
  return Run(&job, stats);
}

Status RayMarcher::RenderRays(size_t count, const float* origins, const float* dirs, float* rgb,
                              float* acc, RenderStats* stats) {
  ECRF_CHECK_OR_RETURN(scene_ != nullptr, kErrInvalidArgument, "render: Init first");
  if (stats != nullptr) *stats = RenderStats();
  if (count == 0) return Status::Ok();
  ECRF_CHECK_OR_RETURN(origins != nullptr && dirs != nullptr && rgb != nullptr, kErrInvalidArgument,
                       "render: null ray or output buffer");
  ECRF_CHECK_OR_RETURN(count <= static_cast<size_t>(-1) / 4, kErrLimit, "render: too many rays");
  Job job;
  job.count = count;
  job.origins = origins;
  job.dirs = dirs;
  job.rgb = rgb;
  job.acc = acc;
  const size_t tr = static_cast<size_t>(options_.tile_size) * options_.tile_size;
  job.num_tiles = (count + tr - 1) / tr;
  return Run(&job, stats);
}

}  // namespace dec
}  // namespace ecrf
