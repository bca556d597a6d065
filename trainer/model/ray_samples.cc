#include "trainer/model/ray_samples.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "decoder/contraction.h"
#include "decoder/ndc.h"
#include "trainer/model/volume_render.h"

namespace ecrf {
namespace trainer {
namespace march {
namespace {

inline bool SameCell(const GridPoint& a, const GridPoint& b) {
  return a.i0[0] == b.i0[0] && a.i0[1] == b.i0[1] && a.i0[2] == b.i0[2];
}

inline void PointAt(const float* o, const float* d, float t, float x[3]) {
  x[0] = o[0] + d[0] * t;
  x[1] = o[1] + d[1] * t;
  x[2] = o[2] + d[2] * t;
}

inline void ToGridPoint(const MarchParams& p, const float x[3], GridPoint* gp) {
  float c[3];
  for (int a = 0; a < 3; ++a) c[a] = (x[a] - p.box.min[a]) * p.inv_size[a] - 1.f;
  LocateGridPoint(c, p.res, gp);
}

// Candidates of an unbounded scene (SPEC.md 7.2.1, the decoder's MarchRayUnbounded): from near
// on (shifted by jitter times the first interval in training), spaced `step` in contracted
// distance. The last sample (dist 0) never contributes and is left out.
void UnboundedCandidates(const MarchParams& p, const float* o, const float* d, float jitter,
                         std::vector<Candidate>& cand) {
  const ContractedRay ray(o, d, p.roi_min, p.roi_scale, p.step);
  float q[3], x[3];
  float t = p.near;
  if (jitter > 0.f) {
    ray.At(t, q, x);
    const float first = ray.Increment(q);
    if (std::isfinite(first)) t = t + jitter * first;
  }
  for (int i = 0; i + 1 < p.n_samples; ++i) {
    ray.At(t, q, x);
    const float next = t + ray.Increment(q);
    if (!std::isfinite(next)) break;
    if (!p.mask || p.mask->Occupied(x)) {
      Candidate c;
      c.t = t;
      c.s = static_cast<float>(i) + jitter;
      c.dscale = (next - t) * p.distance_scale;
      ToGridPoint(p, x, &c.gp);
      cand.push_back(c);
    }
    t = next;
  }
}

// Samples inside the aabb and the alpha mask (no feature lookups) of an object scene.
void ObjectCandidates(const MarchParams& p, const float* o, const float* d, float jitter,
                      std::vector<Candidate>& cand) {
  float t_enter, t_exit;
  RayAabb(p.box, o, d, &t_enter, &t_exit);
  const float t_min = std::min(std::max(t_enter, p.near), p.far);
  // Index range that can be inside the box (with a margin; the exact test follows). The last
  // sample (dist 0, alpha 0) never contributes and is skipped.
  const double a = (static_cast<double>(t_enter) - t_min) / p.step - jitter;
  const double b = (static_cast<double>(t_exit) - t_min) / p.step - jitter;
  if (!(b >= -2.0)) return;
  const int last = p.n_samples - 1;
  const int i_lo = a > 0 ? static_cast<int>(std::min<double>(std::floor(a) - 1, last)) : 0;
  const int i_hi = static_cast<int>(std::min<double>(std::ceil(b) + 2, last));
  for (int i = std::max(i_lo, 0); i < i_hi; ++i) {
    const float ri = static_cast<float>(i) + jitter;
    const float t = t_min + p.step * ri;
    float x[3];
    PointAt(o, d, t, x);
    if (x[0] < p.box.min[0] || x[0] > p.box.max[0] || x[1] < p.box.min[1] || x[1] > p.box.max[1] ||
        x[2] < p.box.min[2] || x[2] > p.box.max[2])
      continue;
    if (p.mask && !p.mask->Occupied(x)) continue;
    Candidate c;
    c.t = t;
    c.s = ri;
    c.dscale = p.dscale;
    ToGridPoint(p, x, &c.gp);
    cand.push_back(c);
  }
}

}  // namespace

MarchParams MakeMarchParams(const TensorfModel& model) {
  MarchParams p;
  const TensorfConfig& c = model.config();
  p.box = model.aabb();
  for (int a = 0; a < 3; ++a) p.inv_size[a] = 2.0f / (p.box.max[a] - p.box.min[a]);
  p.res = model.res();
  p.near = c.near;
  p.far = c.far;
  p.step = model.step_size();
  p.dscale = model.step_size() * c.distance_scale;
  p.activation = c.density_activation;
  p.shift = c.density_shift;
  p.weight_threshold = c.weight_threshold;
  p.early_stop = c.early_stop_transmittance;
  p.n_samples = model.n_samples();
  p.mask = model.alpha_mask();
  p.density = &model.density();
  p.unbounded = c.scene_model == SceneModel::kUnbounded;
  p.forward = c.scene_model == SceneModel::kForward;
  p.ndc = c.ndc;
  p.distance_scale = c.distance_scale;
  for (int a = 0; a < 3; ++a) {
    p.roi_min[a] = c.roi.min[a];
    p.roi_scale[a] = 1.0f / (c.roi.max[a] - c.roi.min[a]) * 2.f;
  }
  if (p.n_samples < 1) throw std::runtime_error("volume render: model has no samples per ray");
  if (model.res()[0] < 2) throw std::runtime_error("volume render: model is not initialized");
  return p;
}

int MarchRay(const MarchParams& p, const float* o, const float* d, float jitter,
             std::vector<Candidate>& cand, std::vector<SampleRec>& buf, int* count) {
  *count = 0;
  // Pass 1: the samples to evaluate (no feature lookups).
  cand.clear();
  if (p.unbounded) {
    UnboundedCandidates(p, o, d, jitter, cand);
  } else if (p.forward) {
    float ndc_o[3], ndc_d[3];
    if (NdcRay(p.ndc, o, d, ndc_o, ndc_d)) ObjectCandidates(p, ndc_o, ndc_d, jitter, cand);
  } else {
    ObjectCandidates(p, o, d, jitter, cand);
  }
  // Pass 2: density, alpha, transmittance (prefetching the grid a few samples ahead).
  float trans = 1.f;
  int n_app = 0;
  const size_t start = buf.size();
  const int nc = static_cast<int>(cand.size());
  for (int k = 0; k < std::min(nc, kPrefetchDistance); ++k) p.density->Prefetch(cand[k].gp);
  for (int k = 0; k < nc; ++k) {
    if (k + kPrefetchDistance < nc &&
        !SameCell(cand[k + kPrefetchDistance].gp, cand[k + kPrefetchDistance - 1].gp))
      p.density->Prefetch(cand[k + kPrefetchDistance].gp);
    const float feat = p.density->Density(cand[k].gp) + p.shift;
    const float sigma = ActivateDensity(p.activation, feat);
    const float alpha = 1.f - std::exp(-sigma * cand[k].dscale);
    const float w = alpha * trans;
    SampleRec rec;
    rec.gp = cand[k].gp;
    rec.t = cand[k].t;
    rec.s = cand[k].s;
    rec.dscale = cand[k].dscale;
    rec.feat = feat;
    rec.alpha = alpha;
    rec.trans = trans;
    rec.app = w > p.weight_threshold ? n_app++ : -1;
    buf.push_back(rec);
    trans *= (1.f - alpha) + 1e-10f;
    if (trans < p.early_stop) break;
  }
  *count = static_cast<int>(buf.size() - start);
  return n_app;
}

}  // namespace march

float RayJitter(uint64_t seed, int64_t ray) {
  const uint64_t h = march::SplitMix64(march::SplitMix64(seed) ^
                                       (static_cast<uint64_t>(ray) * 0xD1B54A32D192ED03ull));
  return static_cast<float>(h >> 40) * (1.0f / 16777216.0f);
}

std::vector<RaySampleInfo> TraceRay(const TensorfModel& model, const float o[3], const float d[3],
                                    float jitter) {
  const march::MarchParams p = march::MakeMarchParams(model);
  std::vector<march::SampleRec> buf;
  std::vector<march::Candidate> cand;
  int count = 0;
  march::MarchRay(p, o, d, jitter, cand, buf, &count);
  std::vector<RaySampleInfo> out(buf.size());
  for (size_t k = 0; k < buf.size(); ++k) {
    out[k].t = buf[k].t;
    out[k].sigma = ActivateDensity(p.activation, buf[k].feat);
    out[k].alpha = buf[k].alpha;
    out[k].weight = buf[k].alpha * buf[k].trans;
    out[k].colour = buf[k].app >= 0;
  }
  return out;
}

}  // namespace trainer
}  // namespace ecrf
