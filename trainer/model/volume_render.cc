#include "trainer/model/volume_render.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <stdexcept>
#include <vector>

#include "trainer/model/ray_batch.h"
#include "trainer/model/ray_samples.h"

namespace ecrf {
namespace trainer {
namespace {

using batch::CompositeBackward;
using batch::CompositeForward;
using batch::DeferredChunk;
using batch::EnsureSize;
using batch::kMinParallelRays;
using batch::NextChunk;
using batch::PixelLoss;
using batch::RayChunk;
using batch::RayComposite;
using batch::RayLoss;
using batch::RayRec;
using batch::SumRayProducts;
using batch::Workspace;
using march::Candidate;
using march::kPrefetchDistance;
using march::MakeMarchParams;
using march::MarchParams;
using march::MarchRay;
using march::SampleRec;
using march::SplitMix64;

constexpr int kScatterTile = 32;  // plane vertices per side of a scatter tile

// Scatter tiles along a plane axis of `res` vertices.
inline int TilesAlong(int res) { return (res + kScatterTile - 1) / kScatterTile; }

// Phase 1: march all rays, assign appearance rows; returns the number of appearance samples.
int64_t MarchBatch(const MarchParams& p, Workspace& ws, int n_rays, const float* origins,
                   const float* dirs, bool train, uint64_t seed) {
#pragma omp parallel if (n_rays >= kMinParallelRays)
  {
    const int tid = omp_get_thread_num();
    std::vector<SampleRec>& buf = ws.per_thread[tid].samples;
    std::vector<Candidate>& cand = ws.per_thread[tid].candidates;
#pragma omp for schedule(dynamic, 16)
    for (int r = 0; r < n_rays; ++r) {
      const float jitter = train ? RayJitter(seed, r) : 0.f;
      RayRec& rr = ws.rays[r];
      rr.tid = tid;
      rr.offset = buf.size();
      rr.app_count = MarchRay(p, origins + 3 * r, dirs + 3 * r, jitter, cand, buf, &rr.count);
    }
  }
  int64_t n_app = 0;
  for (int r = 0; r < n_rays; ++r) {
    ws.rays[r].app_start = n_app;
    n_app += ws.rays[r].app_count;
  }
  return n_app;
}

// Appearance products and view directions of the appearance samples of rays [r0, r1), into
// rows 0..rows-1 (row = app_start - base + local index).
void GatherAppearance(const VmGrid& app, Workspace& ws, int r0, int r1, const float* dirs,
                      int64_t base, int64_t rows) {
  const int P = app.total_rank();
  EnsureSize(ws.products, static_cast<size_t>(rows) * P);
  EnsureSize(ws.viewdirs, static_cast<size_t>(rows) * 3);
#pragma omp parallel for schedule(dynamic, 16) if (r1 - r0 >= kMinParallelRays)
  for (int r = r0; r < r1; ++r) {
    const RayRec& rr = ws.rays[r];
    if (rr.app_count == 0) continue;
    const SampleRec* s = ws.SamplesOf(rr);
    const float* d = dirs + 3 * r;
    for (int k = 0; k < rr.count; ++k) {
      if (s[k].app < 0) continue;
      const int64_t row = rr.app_start - base + s[k].app;
      app.Products(s[k].gp, ws.products.data() + static_cast<size_t>(row) * P);
      float* vd = ws.viewdirs.data() + static_cast<size_t>(row) * 3;
      vd[0] = d[0];
      vd[1] = d[1];
      vd[2] = d[2];
    }
  }
}

// Scatters the gradients of rays [r0, r1) into the grids. Each (grid, mode) plane is cut into
// fixed kScatterTile^2-vertex tiles; the samples are bucketed by the tiles their corners touch
// (one task per grid and mode, in ray order), then one task per tile adds them in that order
// (ModeGradScatter::BindTile), the tile's plane vertices and, for the samples whose lower corner
// it holds, a line of its own; the lines are then summed into the grid tile by tile. The tiling
// depends on the grid's size only, so every sum is the same for any thread count; it gives the
// scatter as many tasks as tiles (96 at 128^3) instead of one per (grid, mode), whose longest walk
// over every density sample was the phase's critical path beyond 4 threads.
// With the deferred head a sample's products gradient is its weight times its ray's
// (ws.ray_dl_dproducts), read from there instead of from a row of its own.
void ScatterChunk(VmGrid& density, VmGrid& appearance, Workspace& ws, int r0, int r1, int64_t base,
                  int P, bool deferred) {
  const bool parallel = r1 - r0 >= kMinParallelRays;
  // 1. Bucketing, one task per (grid, mode).
#pragma omp parallel for schedule(dynamic, 1) if (parallel)
  for (int task = 0; task < 6; ++task) {
    const bool is_density = task < 3;
    const int m = task % 3;
    VmGrid& grid = is_density ? density : appearance;
    const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
    Workspace::ModeTiles& mt = ws.tiles[task];
    mt.tiles_x = TilesAlong(grid.res()[u]);
    mt.tiles_y = TilesAlong(grid.res()[v]);
    mt.line_floats = grid.res()[w] * grid.ranks()[m];
    const size_t n_tiles = static_cast<size_t>(mt.tiles_x) * mt.tiles_y;
    if (mt.lists.size() < n_tiles) mt.lists.resize(n_tiles);
    for (size_t t = 0; t < n_tiles; ++t) mt.lists[t].clear();
    const int mode_offset = appearance.rank_offset(m);
    for (int r = r0; r < r1; ++r) {
      const RayRec& rr = ws.rays[r];
      if (!is_density && rr.app_count == 0) continue;
      const SampleRec* s = ws.SamplesOf(rr);
      const float* dprod =
          deferred
              ? ws.ray_dl_dproducts.data() +
                    static_cast<size_t>(std::max(0, ws.head_rays[r - r0].row)) * P + mode_offset
              : ws.dl_dproducts.data() + static_cast<size_t>(rr.app_start - base) * P + mode_offset;
      for (int k = 0; k < rr.count; ++k) {
        Workspace::ScatterEntry e{&s[k].gp, 0.f, nullptr};
        if (is_density) {
          if (s[k].feat == 0.f) continue;
          e.g = s[k].feat;
        } else {
          if (s[k].app < 0) continue;
          e.g = deferred ? s[k].alpha * s[k].trans : 1.f;
          e.dprod = deferred ? dprod : dprod + static_cast<size_t>(s[k].app) * P;
        }
        const int x = s[k].gp.i0[u], y = s[k].gp.i0[v];
        const int tx0 = x / kScatterTile, ty0 = y / kScatterTile;
        const int tx1 = std::min((x + 1) / kScatterTile, mt.tiles_x - 1);
        const int ty1 = std::min((y + 1) / kScatterTile, mt.tiles_y - 1);
        for (int ty = ty0; ty <= ty1; ++ty)
          for (int tx = tx0; tx <= tx1; ++tx) mt.lists[ty * mt.tiles_x + tx].push_back(e);
      }
    }
    mt.line_sums.assign(n_tiles * static_cast<size_t>(mt.line_floats), 0.f);
  }
  // 2. One task per non-empty tile, the largest first (the order changes no sum).
  ws.tile_tasks.clear();
  for (int task = 0; task < 6; ++task) {
    const Workspace::ModeTiles& mt = ws.tiles[task];
    for (int t = 0; t < mt.tiles_x * mt.tiles_y; ++t)
      if (!mt.lists[t].empty()) ws.tile_tasks.push_back({task, t, mt.lists[t].size()});
  }
  std::sort(
      ws.tile_tasks.begin(), ws.tile_tasks.end(),
      [](const Workspace::TileTask& a, const Workspace::TileTask& b) {
        return a.entries != b.entries
                   ? a.entries > b.entries
                   : (a.mode_task != b.mode_task ? a.mode_task < b.mode_task : a.tile < b.tile);
      });
  if (ws.scatter.size() < ws.tile_tasks.size()) ws.scatter.resize(ws.tile_tasks.size());
  const int n_tasks = static_cast<int>(ws.tile_tasks.size());
#pragma omp parallel for schedule(dynamic, 1) if (parallel)
  for (int k = 0; k < n_tasks; ++k) {
    const Workspace::TileTask& tt = ws.tile_tasks[k];
    const bool is_density = tt.mode_task < 3;
    const int m = tt.mode_task % 3;
    VmGrid& grid = is_density ? density : appearance;
    Workspace::ModeTiles& mt = ws.tiles[tt.mode_task];
    const int tx = tt.tile % mt.tiles_x, ty = tt.tile / mt.tiles_x;
    ModeGradScatter& sc = ws.scatter[k];
    sc.BindTile(&grid, m, tx * kScatterTile, (tx + 1) * kScatterTile, ty * kScatterTile,
                (ty + 1) * kScatterTile,
                mt.line_sums.data() + static_cast<size_t>(tt.tile) * mt.line_floats);
    const std::vector<Workspace::ScatterEntry>& list = mt.lists[tt.tile];
    const size_t n = list.size();
    for (size_t i = 0; i < n; ++i) {
      if (i + kPrefetchDistance < n) {
        grid.PrefetchMode(*list[i + kPrefetchDistance].gp, m, false);
        grid.PrefetchMode(*list[i + kPrefetchDistance].gp, m, true);
      }
      if (is_density) {
        sc.AddDensity(*list[i].gp, list[i].g);
      } else {
        sc.AddProducts(*list[i].gp, list[i].dprod, list[i].g);
      }
    }
    sc.Flush();
  }
  // 3. The lines: each (grid, mode)'s tile sums added in tile order.
#pragma omp parallel for schedule(dynamic, 1) if (parallel)
  for (int task = 0; task < 6; ++task) {
    const int m = task % 3;
    VmGrid& grid = task < 3 ? density : appearance;
    const Workspace::ModeTiles& mt = ws.tiles[task];
    float* line = grid.line_grad(m);
    const int n_tiles = mt.tiles_x * mt.tiles_y;
    for (int t = 0; t < n_tiles; ++t) {
      if (mt.lists[t].empty()) continue;
      const float* sums = mt.line_sums.data() + static_cast<size_t>(t) * mt.line_floats;
      for (int j = 0; j < mt.line_floats; ++j) line[j] += sums[j];
    }
  }
}

// Compositing forward, loss and compositing backward (dL/dfeature, dL/drgb) of a chunk's rays,
// whose head outputs are in ws.rgb. The sums are the step's OpenMP reduction variables. Each
// thread takes its own copy of the loss, which lets the compiler keep it in registers.
void CompositeChunk(RayLoss loss, Workspace& ws, const RayChunk& chunk, double& sse,
                    long& n_density, double& distortion_sum) {
  const int64_t base = chunk.base;
#pragma omp parallel for schedule(dynamic, 16) firstprivate(loss) \
    reduction(+ : sse, n_density, distortion_sum) if (chunk.r1 - chunk.r0 >= kMinParallelRays)
  for (int r = chunk.r0; r < chunk.r1; ++r) {
    const RayRec& rr = ws.rays[r];
    SampleRec* s = ws.SamplesOf(rr);
    const int64_t row0 = rr.app_start - base;
    n_density += rr.count;
    RayComposite rc = CompositeForward(loss, s, rr.count, ws.rgb.data(), row0);
    float g[3];
    PixelLoss(loss, r, rc, g, sse);
    const float* rgb_rows = ws.rgb.data();
    float* dl_drgb_rows = ws.dl_drgb.data();
    // The per-sample head: the sample's colour in its pixel, and dL/drgb = w G for its row.
    distortion_sum +=
        CompositeBackward(loss, s, rr.count, rc, g, [&](const SampleRec& sk, float w) {
          const int64_t row = row0 + sk.app;
          const float* rgb = rgb_rows + 3 * row;
          float* dr = dl_drgb_rows + 3 * row;
          dr[0] = w * g[0];
          dr[1] = w * g[1];
          dr[2] = w * g[2];
          return g[0] * rgb[0] + g[1] * rgb[1] + g[2] * rgb[2];
        });
  }
}

}  // namespace

int ScatterTaskCount(const TensorfModel& model) {
  int tasks = 0;
  for (const VmGrid* g : {&model.density(), &model.appearance()})
    for (int m = 0; m < 3; ++m)
      tasks += TilesAlong(g->res()[kMatMode[m][0]]) * TilesAlong(g->res()[kMatMode[m][1]]);
  return tasks;
}

TrainStepStats TrainStep(TensorfModel& model, int n_rays, const float* origins, const float* dirs,
                         const float* target_rgb, uint64_t rng_seed, float distortion_weight,
                         const float* ray_gain, float* dl_dgain) {
  TrainStepStats stats;
  stats.rays = n_rays;
  if (n_rays <= 0) return stats;
  if (!model.train_workspace) model.train_workspace = std::make_shared<Workspace>();
  Workspace& ws = *static_cast<Workspace*>(model.train_workspace.get());
  const int threads = omp_get_max_threads();
  ws.Prepare(n_rays, threads);
  const MarchParams p = MakeMarchParams(model);
  const TensorfConfig& cfg = model.config();
  const bool white =
      cfg.white_background || (SplitMix64(rng_seed ^ 0x5DEECE66Dull) >> 63) != 0;  // rand < 0.5

  double clock = omp_get_wtime();
  auto lap = [&clock]() {
    const double now = omp_get_wtime();
    const double dt = now - clock;
    clock = now;
    return dt;
  };
  // Phase 1: march all rays (sampling, mask, density forward).
  const int64_t n_app = MarchBatch(p, ws, n_rays, origins, dirs, /*train=*/true, rng_seed);
  stats.t_march = lap();
  stats.appearance_samples = n_app;

  const int P = model.appearance().total_rank();
  VmGrid& density = model.density();
  VmGrid& appearance = model.appearance();
  AppearanceHead& head = model.head();
  const RayLoss loss{target_rgb,
                     ray_gain,
                     dl_dgain,
                     white,
                     cfg.density_activation,
                     2.f / (3.f * static_cast<float>(n_rays)),
                     distortion_weight > 0.f,
                     1.0 / p.n_samples,
                     static_cast<double>(distortion_weight) / n_rays};
  const int64_t max_rows = std::max(1, cfg.head_chunk_rows);
  // Each chunk's ws.products stays untouched until its head.Backward, so the head need not copy it.
  head.set_borrow_products(true);
  const bool deferred = cfg.head.kind == HeadKind::kDeferred;
  double sse = 0.0;
  long n_density = 0;
  double distortion_sum = 0.0;

  // The rest runs per chunk of consecutive rays holding at most head_chunk_rows appearance
  // samples (the loss is a sum over rays), bounding the head's activation memory.
  for (int r0 = 0; r0 < n_rays;) {
    const RayChunk chunk = NextChunk(ws, r0, n_rays, max_rows);
    const int64_t rows = chunk.rows;

    // Appearance inputs + head forward.
    GatherAppearance(appearance, ws, chunk.r0, chunk.r1, dirs, chunk.base, rows);
    if (deferred) {
      DeferredChunk(loss, head, ws, chunk, P, dirs, stats, lap, sse, n_density, distortion_sum);
      ScatterChunk(density, appearance, ws, chunk.r0, chunk.r1, chunk.base, P, deferred);
      stats.t_scatter += lap();
      r0 = chunk.r1;
      continue;
    }
    EnsureSize(ws.rgb, static_cast<size_t>(rows) * 3);
    EnsureSize(ws.dl_drgb, static_cast<size_t>(rows) * 3);
    stats.t_march += lap();
    stats.head_rows += rows;
    if (rows > 0)
      head.Forward(static_cast<int>(rows), ws.products.data(), ws.viewdirs.data(), ws.rgb.data());
    stats.t_head += lap();

    CompositeChunk(loss, ws, chunk, sse, n_density, distortion_sum);
    stats.t_composite += lap();

    // Head backward.
    EnsureSize(ws.dl_dproducts, static_cast<size_t>(rows) * P);
    if (rows > 0) head.Backward(static_cast<int>(rows), ws.dl_drgb.data(), ws.dl_dproducts.data());
    stats.t_head += lap();

    ScatterChunk(density, appearance, ws, chunk.r0, chunk.r1, chunk.base, P, deferred);
    stats.t_scatter += lap();
    r0 = chunk.r1;
  }
  stats.mse = sse / (3.0 * n_rays);
  stats.distortion = distortion_sum / n_rays;
  stats.loss = stats.mse + distortion_weight * stats.distortion;
  stats.density_samples = n_density;
  return stats;
}

void RenderRays(const TensorfModel& model, int n_rays, const float* origins, const float* dirs,
                float* rgb_out, float* depth_or_null, const float* ray_gain) {
  if (n_rays <= 0) return;
  const MarchParams p = MakeMarchParams(model);
  const bool white = model.config().white_background;
  Workspace ws;
  const int threads = omp_get_max_threads();
  const int kChunk = 1024;
  for (int begin = 0; begin < n_rays; begin += kChunk) {
    const int n = std::min(kChunk, n_rays - begin);
    const float* o = origins + 3 * static_cast<size_t>(begin);
    const float* d = dirs + 3 * static_cast<size_t>(begin);
    ws.Prepare(n, threads);
    const int64_t n_app = MarchBatch(p, ws, n, o, d, /*train=*/false, 0);
    GatherAppearance(model.appearance(), ws, 0, n, d, 0, n_app);
    const bool deferred = model.config().head.kind == HeadKind::kDeferred;
    if (deferred) {
      const int rows = SumRayProducts(ws, 0, n, 0, model.appearance().total_rank(), d);
      EnsureSize(ws.ray_rgb, static_cast<size_t>(rows) * 3);
      if (rows > 0)
        model.head().Infer(rows, ws.ray_products.data(), ws.ray_viewdirs.data(), ws.ray_rgb.data());
    }
    EnsureSize(ws.rgb, static_cast<size_t>(n_app) * 3);
    if (n_app > 0 && !deferred)
      model.head().Infer(static_cast<int>(n_app), ws.products.data(), ws.viewdirs.data(),
                         ws.rgb.data());
#pragma omp parallel for schedule(dynamic, 16) if (n >= kMinParallelRays)
    for (int r = 0; r < n; ++r) {
      const RayRec& rr = ws.rays[r];
      const SampleRec* s = ws.SamplesOf(rr);
      float c[3] = {0.f, 0.f, 0.f};
      float acc = 0.f, depth = 0.f;
      for (int k = 0; k < rr.count; ++k) {
        const float w = s[k].alpha * s[k].trans;
        acc += w;
        depth += w * s[k].t;
        if (s[k].app >= 0 && !deferred) {
          const float* rgb = ws.rgb.data() + 3 * (rr.app_start + s[k].app);
          c[0] += w * rgb[0];
          c[1] += w * rgb[1];
          c[2] += w * rgb[2];
        }
      }
      if (deferred && ws.head_rays[r].row >= 0) {
        const Workspace::HeadRay& hr = ws.head_rays[r];
        const float* rgb = ws.ray_rgb.data() + 3 * static_cast<size_t>(hr.row);
        for (int ch = 0; ch < 3; ++ch) c[ch] = hr.weight * rgb[ch];
      }
      float* out = rgb_out + 3 * (static_cast<size_t>(begin) + r);
      const float* gain = ray_gain ? ray_gain + 3 * (static_cast<size_t>(begin) + r) : nullptr;
      for (int ch = 0; ch < 3; ++ch) {
        if (white) c[ch] += 1.f - acc;
        if (gain) c[ch] *= gain[ch];
        out[ch] = std::min(std::max(c[ch], 0.f), 1.f);
      }
      if (depth_or_null) depth_or_null[begin + r] = depth;
    }
  }
}

double RenderMse(const TensorfModel& model, int n, const float* origins, const float* dirs,
                 const float* rgb, const float* ray_gain) {
  std::vector<float> out(static_cast<size_t>(n) * 3);
  RenderRays(model, n, origins, dirs, out.data(), nullptr, ray_gain);
  double sum = 0.0;
  for (size_t i = 0; i < out.size(); ++i) {
    const double e = double(out[i]) - rgb[i];
    sum += e * e;
  }
  return sum / static_cast<double>(out.size());
}

}  // namespace trainer
}  // namespace ecrf
