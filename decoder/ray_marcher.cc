#include "decoder/ray_marcher.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <functional>
#include <new>
#include <thread>

#include "decoder/contraction.h"
#include "decoder/ray_march.h"

namespace ecrf {
namespace dec {

namespace {

uint8_t ToByte(float v) { return static_cast<uint8_t>(ClipUnit(v) * 255.f + 0.5f); }

// pixels x work_budget (0: no limit), saturated rather than wrapped (pixels < 2^62).
int64_t ViewBudget(uint64_t pixels, uint64_t budget) {
  const int64_t kUnlimited = INT64_MAX / 2;
  return budget == 0 || pixels > static_cast<uint64_t>(kUnlimited) / budget
             ? kUnlimited
             : static_cast<int64_t>(pixels * budget);
}

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
  view_ = false;
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
  const SampleCosts costs = SceneSampleCosts(*scene);
  if (options.work_budget > 0) {
    const uint64_t sample = costs.position + costs.density + costs.color + costs.ray_head;
    ECRF_CHECK_OR_RETURN(
        sample <= options.work_budget, kErrLimit,
        "render: one coloured sample of this scene costs %llu multiply-adds (%s head, MLP of %d "
        "features, %d hidden, %d products), more than the work budget of %llu per pixel "
        "(RenderOptions::work_budget; ecrf --work-budget N, 0 for no limit)",
        static_cast<unsigned long long>(sample), HeadKindName(scene->head),
        scene->mlp.config().feature_dim, scene->mlp.config().hidden, scene->appearance.total_rank(),
        static_cast<unsigned long long>(options.work_budget));
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
    if (scene->head == HeadKind::kDeferred) {
      ECRF_RETURN_IF_ERROR(ws.ray_products.Allocate(static_cast<size_t>(tile_rays) * pstride));
      ECRF_RETURN_IF_ERROR(ws.ray_color_weight.Allocate(static_cast<size_t>(tile_rays)));
    }
    ws.pstride = pstride;
    ws.capacity = options.batch_rows;
  }
  scene_ = scene;
  options_ = options;
  threads_ = threads;
  costs_ = costs;
  return Status::Ok();
}

namespace {

void Worker(const Ctx& c, RayMarcher::Job* job, RayMarcher::Workspace* ws);

}  // namespace

void RayMarcher::BeginView(uint64_t view_pixels) {
  view_ = true;
  view_pixels_ = view_pixels;
  view_left_ = ViewBudget(view_pixels, options_.work_budget);
}

Status RayMarcher::Run(Job* job, uint64_t pixels, RenderStats* stats) {
  const SceneField& s = *scene_;
  Ctx c;
  c.s = &s;
  c.unbounded = s.scene_model == SceneModel::kUnbounded;
  c.forward = s.scene_model == SceneModel::kForward;
  c.deferred = s.head == HeadKind::kDeferred;
  for (int a = 0; a < 3; ++a) {
    c.roi_min[a] = s.aabb_min[a];
    c.roi_scale[a] = 1.0f / (s.aabb_max[a] - s.aabb_min[a]) * 2.f;
    c.min[a] = c.unbounded ? -kContractedExtent : s.aabb_min[a];
    c.max[a] = c.unbounded ? kContractedExtent : s.aabb_max[a];
    c.inv[a] = 1.0f / (c.max[a] - c.min[a]) * 2.f;
  }
  c.step = s.StepSize();
  if (options_.step_scale != 1.f) c.step *= options_.step_scale;
  c.inv_step = 1.0 / static_cast<double>(c.step);
  c.n = SamplesPerRay(s, options_);
  c.near = s.near_far[0];
  c.far = s.near_far[1];
  c.activation = s.density_activation;
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
  c.cost = costs_;

  const uint64_t budget = options_.work_budget;
  if (view_) pixels = view_pixels_;  // the refusal names the view
  job->work_left.store(view_ ? view_left_ : ViewBudget(pixels, budget));
  for (int t = 0; t < threads_; ++t) {
    workspaces_[t].stats = RenderStats();
    workspaces_[t].credit = 0;
    workspaces_[t].pool = &job->work_left;
    workspaces_[t].exhausted = &job->exhausted;
  }
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
  RenderStats total;
  for (int t = 0; t < threads_; ++t) total.Add(workspaces_[t].stats);
  if (view_) {  // what the threads took from the pool and did not spend goes back to the view
    int64_t left = job->work_left.load();
    for (int t = 0; t < threads_; ++t)
      left += workspaces_[t].credit > 0 ? workspaces_[t].credit : 0;
    view_left_ = left;
  }
  if (stats != nullptr) *stats = total;
  ECRF_CHECK_OR_RETURN(
      !job->exhausted.load(), kErrLimit,
      "render: the view spent its work budget of %llu multiply-adds (%llu per pixel x %llu "
      "pixels) before it was done (rays of this scene cost up to %llu each: %d samples); "
      "RenderOptions::work_budget, ecrf --work-budget N (0: no limit), or fewer samples with "
      "--samples N or --step-scale S",
      static_cast<unsigned long long>(pixels * budget), static_cast<unsigned long long>(budget),
      static_cast<unsigned long long>(pixels),
      static_cast<unsigned long long>(costs_.WorstRay(c.n)), c.n);
  return Status::Ok();
}

namespace {

void Worker(const Ctx& c, RayMarcher::Job* job, RayMarcher::Workspace* ws) {
  for (;;) {
    if (job->exhausted.load(std::memory_order_relaxed)) break;
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
  return Run(&job, static_cast<uint64_t>(camera.width) * static_cast<uint64_t>(camera.height),
             stats);
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
  return Run(&job, count, stats);
}

}  // namespace dec
}  // namespace ecrf
