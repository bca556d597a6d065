// The marching of rays (SPEC.md 7.2-7.5, 7.8) for RayMarcher: the object, unbounded and
// forward-facing processes, empty-space skipping, compositing, the batched MLP, and the charges
// against the view's work budget (decoder/render_work.h).
#include "decoder/ray_march.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "decoder/contraction.h"
#include "decoder/field_sampler.h"
#include "decoder/ndc.h"

namespace ecrf {
namespace dec {
namespace {

// Threads take the budget in shares of this many multiply-adds, so they rarely touch the pool.
constexpr int64_t kWorkShare = int64_t{1} << 22;

bool RefillCredit(RayMarcher::Workspace& ws) {
  if (ws.exhausted->load(std::memory_order_relaxed)) return false;
  const int64_t need = -ws.credit;
  const int64_t take = need + kWorkShare;
  const int64_t before = ws.pool->fetch_sub(take, std::memory_order_relaxed);
  if (before >= take) {
    ws.credit += take;
    return true;
  }
  // The pool's last share: enough for this charge (the pool is now below zero for the others),
  // or the view has spent its budget.
  if (before >= need) {
    ws.credit += before;
    return true;
  }
  ws.exhausted->store(true, std::memory_order_relaxed);
  return false;
}

// Charges `units` multiply-adds; false once the view has spent its budget.
inline bool Spend(RayMarcher::Workspace& ws, uint64_t units) {
  ws.stats.work += units;
  ws.credit -= static_cast<int64_t>(units);
  return ws.credit >= 0 || RefillCredit(ws);
}

inline float SampleT(float t0, float step, int i) { return t0 + step * static_cast<float>(i); }

// Smallest j in [0, n] with SampleT(j) >= lim (SampleT is non-decreasing in j).
int FirstIndexAtLeast(float t0, float step, int n, double lim) {
  const double est = std::ceil((lim - t0) / step);
  int j = !(est > 0.0) ? 0 : (est >= n ? n : static_cast<int>(est));
  while (j > 0 && static_cast<double>(SampleT(t0, step, j - 1)) >= lim) --j;
  while (j < n && static_cast<double>(SampleT(t0, step, j)) < lim) ++j;
  return j;
}

// Largest j in [i - 1, n - 1] with SampleT(j) <= lim. The estimate by the reciprocal (no
// division: this runs at every skip) is at most one off; the loops make it exact.
int LastIndexAtMost(float t0, float step, double inv_step, int n, int i, double lim) {
  const double est = std::floor((lim - t0) * inv_step);
  int j = !(est > i - 1) ? i - 1 : (est >= n - 1 ? n - 1 : static_cast<int>(est));
  while (j + 1 < n && static_cast<double>(SampleT(t0, step, j + 1)) <= lim) ++j;
  while (j >= i && static_cast<double>(SampleT(t0, step, j)) > lim) --j;
  return j;
}

// The straight ray's line in mask index units, per axis: index(t) = A + D t, with the margin m
// that covers the float rounding of the reference's index computation (7.3). Computed once per
// ray, so that a skip costs multiplications, not divisions.
struct SkipFrame {
  double A[3], inv_D[3], m[3];
  bool moving[3];  // d[a] != 0; a constant index stays inside any block it starts in
};

SkipFrame MakeSkipFrame(const Ctx& c, const float o[3], const float d[3], double tspan) {
  const OccupancyMask& mask = *c.mask;
  SkipFrame f;
  for (int a = 0; a < 3; ++a) {
    const double S = c.mask_scale[a];
    f.moving[a] = d[a] != 0.f;
    f.A[a] = (static_cast<double>(o[a]) - mask.aabb_min()[a]) * S;
    f.inv_D[a] = f.moving[a] ? 1.0 / (static_cast<double>(d[a]) * S) : 0.0;
    f.m[a] = 1e-4 + 2e-6 * mask.res()[a] +
             1e-6 *
                 (std::fabs(o[a]) + std::fabs(d[a]) * tspan + std::fabs(mask.aabb_min()[a]) +
                  std::fabs(mask.aabb_max()[a])) *
                 S;
  }
  return f;
}

// Sample i (mask index idx) lies in an empty block: returns the first sample index past the run of
// samples that provably stay inside an empty region around it (i itself when that cannot be
// proven). The finest level is asked first: each block of a level lies inside its block of the
// coarser level (OccupancyMask), so a sample in an occupied fine block is in an occupied coarse
// one. Two empty regions hold an empty finest block: the coarsest empty aligned block, and the
// empty cube of finest blocks centred on it; the ray leaves one or the other last.
int SkipEmpty(const Ctx& c, const SkipFrame& f, float t0, int i, const float idx[3]) {
  const OccupancyMask& mask = *c.mask;
  const int* res = mask.res();
  for (int a = 0; a < 3; ++a) {
    if (!(idx[a] >= 0.f && idx[a] <= static_cast<float>(res[a] - 1))) return i;
  }
  constexpr int kFinest = OccupancyMask::kLevels - 1;
  int region_lo[2][3], region_hi[2][3];  // the coarsest empty aligned block, then the cube
  if (!mask.EmptyBlock(kFinest, idx, region_lo[0], region_hi[0])) return i;
  std::memcpy(region_lo[1], region_lo[0], sizeof(region_lo[0]));
  std::memcpy(region_hi[1], region_hi[0], sizeof(region_hi[0]));
  const int regions = mask.EmptyCube(region_lo[1], region_hi[1]) > 0 ? 2 : 1;  // 0: the block
  for (int level = 0; level < kFinest; ++level) {  // the coarsest empty block skips furthest
    int clo[3], chi[3];  // EmptyBlock writes its range even when the block is occupied
    if (!mask.EmptyBlock(level, idx, clo, chi)) continue;
    std::memcpy(region_lo[0], clo, sizeof(clo));
    std::memcpy(region_hi[0], chi, sizeof(chi));
    break;
  }
  // Per region, the t-range where the exact position o + d t stays within [lo + m, hi - m] on
  // every axis. The reciprocal's rounding (relative 2^-53) is far inside the margin.
  const double t = SampleT(t0, c.step, i);
  double exit = -INFINITY;
  for (int r = 0; r < regions; ++r) {
    double tlo = -INFINITY, thi = INFINITY;
    for (int a = 0; a < 3; ++a) {
      if (!f.moving[a]) continue;
      double ta = (region_lo[r][a] + f.m[a] - f.A[a]) * f.inv_D[a];
      double tb = (region_hi[r][a] - f.m[a] - f.A[a]) * f.inv_D[a];
      if (ta > tb) std::swap(ta, tb);
      tlo = std::max(tlo, ta);
      thi = std::min(thi, tb);
    }
    if (t >= tlo) exit = std::max(exit, thi);
  }
  if (!(exit > -INFINITY)) return i;
  const int j = LastIndexAtMost(t0, c.step, c.inv_step, c.n, i, exit);
  return j >= i ? j + 1 : i;
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
  const uint64_t wide = c.s->mlp.Infer(n, ws.products.data(), ws.pstride, ws.viewdirs.data(),
                                       ws.colors.data(), ws.mlp_scratch.data());
  if (wide != 0) Spend(ws, wide * kWideSinCosWork);  // past the budget: the view is refused
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

// Deferred head (SPEC.md 7.6): adds the weighted products of a coloured sample to its ray's sums.
void AccumulateProducts(const Ctx& c, RayMarcher::Workspace& ws, int slot, const GridPoint& gp,
                        float weight) {
  AccumulateAppearanceProducts(c.s->appearance, gp, weight,
                               ws.ray_products.data() + static_cast<size_t>(slot) * ws.pstride);
  ws.ray_color_weight[slot] += weight;
  ++ws.stats.color_samples;
}

// Deferred head: the MLP on the summed products of every ray with a coloured sample, its colour
// times the ray's colour weight (SPEC.md 7.6). Rays are batched in ws.capacity rows.
void ShadeRays(const Ctx& c, RayMarcher::Workspace& ws, int nrays) {
  int r = 0;
  while (r < nrays) {
    int n = 0;
    for (; r < nrays && n < ws.capacity; ++r) {
      if (!(ws.ray_color_weight[r] > 0.f)) continue;
      // A view past its budget is refused whole; its remaining rays are left uncoloured.
      if (!Spend(ws, c.cost.ray_head)) return;
      ws.entries[n].slot = r;
      std::memcpy(ws.products.data() + static_cast<size_t>(n) * ws.pstride,
                  ws.ray_products.data() + static_cast<size_t>(r) * ws.pstride,
                  ws.pstride * sizeof(float));
      std::memcpy(ws.viewdirs.data() + static_cast<size_t>(n) * 3,
                  ws.ray_d.data() + static_cast<size_t>(r) * 3, 3 * sizeof(float));
      ++n;
    }
    if (n == 0) break;
    const uint64_t wide = c.s->mlp.Infer(n, ws.products.data(), ws.pstride, ws.viewdirs.data(),
                                         ws.colors.data(), ws.mlp_scratch.data());
    if (wide != 0 && !Spend(ws, wide * kWideSinCosWork)) return;
    for (int e = 0; e < n; ++e) {
      const int slot = ws.entries[e].slot;
      const float w = ws.ray_color_weight[slot];
      float* rgb = ws.ray_rgb.data() + static_cast<size_t>(slot) * 3;
      const float* col = ws.colors.data() + static_cast<size_t>(e) * 3;
      rgb[0] = w * col[0];
      rgb[1] = w * col[1];
      rgb[2] = w * col[2];
    }
  }
}

// Evaluates the sample at grid-box point p (world for the object model, contracted for the
// unbounded one) with interval `dist` and composites it (7.2, 7.5). False once the ray may stop
// early (T below the early-termination threshold).
bool CompositeSample(const Ctx& c, RayMarcher::Workspace& ws, int slot, const float p[3],
                     float dist, float* T, float* acc) {
  if (!Spend(ws, c.cost.density)) return false;
  ++ws.stats.samples;
  float cn[3];
  for (int a = 0; a < 3; ++a) cn[a] = (p[a] - c.min[a]) * c.inv[a] - 1.f;
  GridPoint gp;
  LocateGridPoint(cn, c.s->res, &gp);
  const float sigma = ActivateDensity(c.activation, DensityFeature(c.s->density, gp) + c.shift);
  const float alpha = 1.f - std::exp(-sigma * (dist * c.dscale));
  const float weight = alpha * *T;
  *T *= 1.f - alpha + 1e-10f;
  *acc += weight;
  if (weight > c.wthr) {
    if (!Spend(ws, c.cost.color)) return false;
    if (c.deferred) {
      AccumulateProducts(c, ws, slot, gp, weight);
      return !(*T < c.early);
    }
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
  uint64_t positions = 0;
  const bool skip = c.mask != nullptr && c.skip;
  const SkipFrame frame = skip ? MakeSkipFrame(c, o, d, tspan) : SkipFrame{};
  while (i < n) {
    ++positions;
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
      if (skip) {
        const int j = SkipEmpty(c, frame, t0, i, idx);
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
  Spend(ws, positions * c.cost.position);
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
  int i = 0;
  for (; i < c.n; ++i) {
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
  Spend(ws, static_cast<uint64_t>(i < c.n ? i + 1 : c.n) * c.cost.position);
  ws.ray_acc[slot] = acc;
}

}  // namespace

void ProcessRays(const Ctx& c, RayMarcher::Workspace& ws, int nrays) {
  std::memset(ws.ray_rgb.data(), 0, static_cast<size_t>(nrays) * 3 * sizeof(float));
  if (c.deferred) {
    std::memset(ws.ray_products.data(), 0, static_cast<size_t>(nrays) * ws.pstride * sizeof(float));
    std::memset(ws.ray_color_weight.data(), 0, static_cast<size_t>(nrays) * sizeof(float));
  }
  ws.count = 0;
  for (int r = 0; r < nrays; ++r) {
    // A view past its work budget is refused: its remaining rays are not marched.
    if (ws.exhausted->load(std::memory_order_relaxed)) {
      ws.ray_acc[r] = 0.f;
      continue;
    }
    if (c.unbounded) {
      MarchRayUnbounded(c, ws, r);
    } else if (c.forward) {
      MarchRayForward(c, ws, r);
    } else {
      MarchRay(c, ws, r);
    }
  }
  if (c.deferred) {
    ShadeRays(c, ws, nrays);
  } else {
    Flush(c, ws);
  }
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

}  // namespace dec
}  // namespace ecrf
