// The deferred head in a training step (SPEC.md 7.6): a ray's coloured samples' products summed
// with their weights, the head once per ray, and the compositing backward through both.
//
// pixel = W rgb(S, d) + (1 - acc) background, S = sum_i w_i p_i and W = sum_i w_i over the
// coloured samples i. Through W and S, a coloured sample's weight gets dL/dw_i = G . rgb +
// dL/dS . p_i (G = dL/dpixel), and its products dL/dp_i = w_i dL/dS; every weight also gets
// -G . background through acc, as with the per-sample head.
#include <algorithm>
#include <cstddef>
#include <vector>

#include "trainer/model/ray_batch.h"

namespace ecrf {
namespace trainer {
namespace batch {
namespace {

// a . b in eight interleaved partial sums, which vectorise (a single sum's order would not): the
// order is fixed, so every thread count gets the same bits.
inline float Dot(const float* a, const float* b, int n) {
  float s[8] = {0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f, 0.f};
  int p = 0;
  for (; p + 8 <= n; p += 8) {
    for (int l = 0; l < 8; ++l) s[l] += a[p + l] * b[p + l];
  }
  float tail = 0.f;
  for (; p < n; ++p) tail += a[p] * b[p];
  return (((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]))) + tail;
}

// The deferred head's chunk, between its head's forward (ws.ray_rgb) and backward: compositing
// forward and the loss (pixel = weight * rgb + (1 - acc) * background), dL/drgb of each head row.
void DeferredCompositeForward(RayLoss loss, Workspace& ws, const RayChunk& chunk, double& sse,
                              long& n_density) {
  std::vector<RayComposite>& composites = ws.head_composites;
  composites.resize(static_cast<size_t>(chunk.r1 - chunk.r0));
#pragma omp parallel for schedule(dynamic, 16) firstprivate(loss) \
    reduction(+ : sse, n_density) if (chunk.r1 - chunk.r0 >= kMinParallelRays)
  for (int r = chunk.r0; r < chunk.r1; ++r) {
    const RayRec& rr = ws.rays[r];
    Workspace::HeadRay& hr = ws.head_rays[r - chunk.r0];
    n_density += rr.count;
    RayComposite& rc = composites[r - chunk.r0];
    rc = CompositeForward(loss, ws.SamplesOf(rr), rr.count, nullptr, 0);
    const float* rgb = hr.row >= 0 ? ws.ray_rgb.data() + 3 * static_cast<size_t>(hr.row) : nullptr;
    for (int ch = 0; ch < 3 && rgb; ++ch) rc.c[ch] = hr.weight * rgb[ch];
    PixelLoss(loss, r, rc, hr.g, sse);  // leaves the sums the backward reads (w_total, wm_total)
    if (rgb == nullptr) continue;
    float* dr = ws.ray_dl_drgb.data() + 3 * static_cast<size_t>(hr.row);
    for (int ch = 0; ch < 3; ++ch) dr[ch] = hr.weight * hr.g[ch];
  }
}

// After the head's backward (ws.ray_dl_dproducts = dL/d(summed products)): the compositing
// backward, where a coloured sample's weight reaches the pixel through the ray's colour weight
// and its share of the summed products.
void DeferredCompositeBackward(RayLoss loss, Workspace& ws, const RayChunk& chunk, int P,
                               double& distortion_sum) {
  const std::vector<RayComposite>& composites = ws.head_composites;
#pragma omp parallel for schedule(dynamic, 16) firstprivate(loss) \
    reduction(+ : distortion_sum) if (chunk.r1 - chunk.r0 >= kMinParallelRays)
  for (int r = chunk.r0; r < chunk.r1; ++r) {
    const RayRec& rr = ws.rays[r];
    const Workspace::HeadRay& hr = ws.head_rays[r - chunk.r0];
    const float* rgb = hr.row >= 0 ? ws.ray_rgb.data() + 3 * static_cast<size_t>(hr.row) : nullptr;
    const float* dsum =
        hr.row >= 0 ? ws.ray_dl_dproducts.data() + static_cast<size_t>(hr.row) * P : nullptr;
    const float* g = hr.g;
    const int64_t row0 = rr.app_start - chunk.base;
    const float colour = hr.row >= 0 ? g[0] * rgb[0] + g[1] * rgb[1] + g[2] * rgb[2] : 0.f;
    // A coloured sample's dL/dw through W (the colour) and S. Its products' gradient, w times
    // the ray's, is left to the scatter (ScatterChunk reads the ray's with w as the scale).
    auto through_sum = [&](const SampleRec& sk, float) {
      return colour + Dot(dsum, ws.products.data() + static_cast<size_t>(row0 + sk.app) * P, P);
    };
    distortion_sum += CompositeBackward(loss, ws.SamplesOf(rr), rr.count, composites[r - chunk.r0],
                                        g, through_sum);
  }
}

}  // namespace

int SumRayProducts(Workspace& ws, int r0, int r1, int64_t base, int P, const float* dirs) {
  ws.head_rays.assign(static_cast<size_t>(r1 - r0), Workspace::HeadRay());
  int rows = 0;
  for (int r = r0; r < r1; ++r) {
    if (ws.rays[r].app_count > 0) ws.head_rays[r - r0].row = rows++;
  }
  EnsureSize(ws.ray_products, static_cast<size_t>(rows) * P);
  EnsureSize(ws.ray_viewdirs, static_cast<size_t>(rows) * 3);
#pragma omp parallel for schedule(dynamic, 16) if (r1 - r0 >= kMinParallelRays)
  for (int r = r0; r < r1; ++r) {
    const RayRec& rr = ws.rays[r];
    Workspace::HeadRay& hr = ws.head_rays[r - r0];
    if (hr.row < 0) continue;
    float* sum = ws.ray_products.data() + static_cast<size_t>(hr.row) * P;
    std::fill(sum, sum + P, 0.f);
    const SampleRec* s = ws.SamplesOf(rr);
    for (int k = 0; k < rr.count; ++k) {
      if (s[k].app < 0) continue;
      const float w = s[k].alpha * s[k].trans;
      const float* prod =
          ws.products.data() + static_cast<size_t>(rr.app_start - base + s[k].app) * P;
      for (int p = 0; p < P; ++p) sum[p] += w * prod[p];
      hr.weight += w;
    }
    std::copy(dirs + 3 * r, dirs + 3 * r + 3,
              ws.ray_viewdirs.data() + 3 * static_cast<size_t>(hr.row));
  }
  return rows;
}

void DeferredChunk(const RayLoss& loss, AppearanceHead& head, Workspace& ws, const RayChunk& chunk,
                   int P, const float* dirs, TrainStepStats& stats,
                   const std::function<double()>& lap, double& sse, long& n_density,
                   double& distortion_sum) {
  const int rows = SumRayProducts(ws, chunk.r0, chunk.r1, chunk.base, P, dirs);
  EnsureSize(ws.ray_rgb, static_cast<size_t>(rows) * 3);
  EnsureSize(ws.ray_dl_drgb, static_cast<size_t>(rows) * 3);
  EnsureSize(ws.ray_dl_dproducts, static_cast<size_t>(rows) * P);
  stats.t_march += lap();
  stats.head_rows += rows;
  if (rows > 0)
    head.Forward(rows, ws.ray_products.data(), ws.ray_viewdirs.data(), ws.ray_rgb.data());
  stats.t_head += lap();
  DeferredCompositeForward(loss, ws, chunk, sse, n_density);
  stats.t_composite += lap();
  if (rows > 0) head.Backward(rows, ws.ray_dl_drgb.data(), ws.ray_dl_dproducts.data());
  stats.t_head += lap();
  DeferredCompositeBackward(loss, ws, chunk, P, distortion_sum);
  stats.t_composite += lap();
}

}  // namespace batch
}  // namespace trainer
}  // namespace ecrf
