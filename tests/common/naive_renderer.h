// The naive reference renderer of the decoder tests: a scene builder (random grids, a density
// blob, a mask, a random MLP in the trainer's layout) and a renderer written straight from
// SPEC.md 7 in float64 where the spec allows, one sample at a time, with none of the decoder's
// batching, skipping or SIMD. tests/decoder/ray_marcher_test.cc checks the RayMarcher against it
// ray by ray, grazing and missing rays included.
#ifndef ECRF_TESTS_COMMON_NAIVE_RENDERER_H_
#define ECRF_TESTS_COMMON_NAIVE_RENDERER_H_

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "decoder/field.h"
#include "decoder/field_sampler.h"
#include "decoder/ray_marcher.h"

namespace ecrf {
namespace dec {
namespace naive {

inline constexpr int kMat[3][2] = {{0, 1}, {0, 2}, {1, 2}};
inline constexpr int kVec[3] = {2, 1, 0};

struct TestScene {
  SceneField field;
  std::vector<float> mlp_params;  // trainer layout, for the naive reference
};

struct SceneSpec {
  int res[3] = {9, 11, 7};
  int dranks[3] = {3, 2, 4};
  int aranks[3] = {4, 5, 3};
  int mask_res[3] = {37, 41, 29};  // 0: no mask
  float blob_amp = 3.5f;
  bool empty_mask = false;
  bool random_voxels = true;  // the mask also sets about one voxel in 997 at random
  MlpConfig mlp;
  uint32_t seed = 7;
};

// Random grids plus a separable blob of density, a mask that is a dilated ball plus a few
// random voxels, a random MLP; an off-centre, non-cubic aabb.
inline void BuildScene(const SceneSpec& spec, TestScene* ts) {
  std::mt19937 rng(spec.seed);
  std::normal_distribution<float> nrm(0.f, 1.f);
  std::uniform_real_distribution<float> uni(-1.f, 1.f);
  SceneField& s = ts->field;
  const float mn[3] = {-1.2f, -0.8f, -1.0f}, mx[3] = {1.0f, 1.3f, 0.9f};
  for (int a = 0; a < 3; ++a) {
    s.aabb_min[a] = mn[a];
    s.aabb_max[a] = mx[a];
    s.res[a] = spec.res[a];
  }
  s.near_far[0] = 0.1f;
  s.near_far[1] = 6.f;
  ASSERT_TRUE(s.density.Allocate(spec.res, spec.dranks, GridStorage::kFloat32).ok());
  ASSERT_TRUE(s.appearance.Allocate(spec.res, spec.aranks, GridStorage::kFloat32).ok());
  const float center[3] = {0.2f, -0.15f, 0.1f};
  auto gauss = [&](int axis, int i) {
    const float c = float(i) / float(spec.res[axis] - 1) * 2.f - 1.f;
    const float z = (c - center[axis]) / 0.45f;
    return std::exp(-0.5f * z * z);
  };
  for (int m = 0; m < 3; ++m) {
    for (size_t i = 0; i < s.density.plane_count(m); ++i)
      s.density.plane_f32[m][i] = 0.4f * nrm(rng);
    for (size_t i = 0; i < s.density.line_count(m); ++i) s.density.line_f32[m][i] = 0.4f * nrm(rng);
    for (size_t i = 0; i < s.appearance.plane_count(m); ++i)
      s.appearance.plane_f32[m][i] = 0.5f * nrm(rng);
    for (size_t i = 0; i < s.appearance.line_count(m); ++i)
      s.appearance.line_f32[m][i] = 0.5f * nrm(rng);
    if (spec.dranks[m] > 0) {
      const int u = kMat[m][0], v = kMat[m][1], w = kVec[m];
      for (int y = 0; y < spec.res[v]; ++y)
        for (int x = 0; x < spec.res[u]; ++x)
          s.density.plane_f32[m][s.density.plane_index(m, y, x, 0)] =
              spec.blob_amp * gauss(u, x) * gauss(v, y);
      for (int i = 0; i < spec.res[w]; ++i)
        s.density.line_f32[m][s.density.line_index(m, i, 0)] = gauss(w, i);
    }
  }
  MlpConfig mc = spec.mlp;
  mc.num_products = s.appearance.total_rank();
  ASSERT_TRUE(s.mlp.Init(mc).ok());
  ts->mlp_params.resize(s.mlp.num_params());
  for (float& v : ts->mlp_params) v = 0.3f * uni(rng);
  ASSERT_TRUE(s.mlp.SetParams(ts->mlp_params.data(), ts->mlp_params.size()).ok());
  s.has_mask = spec.mask_res[0] > 0;
  if (s.has_mask) {
    ASSERT_TRUE(s.mask.Init(s.aabb_min, s.aabb_max, spec.mask_res).ok());
    if (!spec.empty_mask) {
      const int* r = spec.mask_res;
      for (int z = 0; z < r[2]; ++z)
        for (int y = 0; y < r[1]; ++y)
          for (int x = 0; x < r[0]; ++x) {
            const float c[3] = {float(x) / (r[0] - 1) * 2 - 1, float(y) / (r[1] - 1) * 2 - 1,
                                float(z) / (r[2] - 1) * 2 - 1};
            float d2 = 0.f;
            for (int a = 0; a < 3; ++a) d2 += (c[a] - center[a]) * (c[a] - center[a]);
            const bool on = d2 < 0.45f * 0.45f || (spec.random_voxels && (rng() % 997) == 0);
            if (on) s.mask.Set(x, y, z, true);
          }
    }
    ASSERT_TRUE(s.mask.BuildAcceleration().ok());
  }
  ASSERT_TRUE(s.Validate().ok()) << s.Validate().message();
}

// ------------------------------------------------------------------------------------------
// Naive reference: TensoRF's inference process written directly (no skipping, no batching).
// Sample positions and mask indices are computed in float as PyTorch does (they decide which
// samples exist); field values, compositing and the MLP run in double.

inline double GridPlane(const VmGrid& g, int m, int y, int x, int r) {
  const size_t i = g.plane_index(m, y, x, r);
  return g.storage == GridStorage::kFloat32 ? double(g.plane_f32[m][i])
                                            : double(g.plane_i16[m][i]) * g.plane_scale[m];
}
inline double GridLine(const VmGrid& g, int m, int k, int r) {
  const size_t i = g.line_index(m, k, r);
  return g.storage == GridStorage::kFloat32 ? double(g.line_f32[m][i])
                                            : double(g.line_i16[m][i]) * g.line_scale[m];
}

struct RefPoint {
  int i0[3];
  double f[3];
};

inline RefPoint Locate(const SceneField& s, const float p[3]) {
  RefPoint rp;
  const bool unbounded = s.scene_model == SceneModel::kUnbounded;  // grids span [-2, 2]^3
  for (int a = 0; a < 3; ++a) {
    const double lo = unbounded ? -2.0 : s.aabb_min[a], hi = unbounded ? 2.0 : s.aabb_max[a];
    const double c = (double(p[a]) - lo) * 2.0 / (hi - lo) - 1.0;
    double idx = (c + 1.0) / 2.0 * (s.res[a] - 1);
    idx = std::min(std::max(idx, 0.0), double(s.res[a] - 1));
    int i = int(std::floor(idx));
    if (i > s.res[a] - 2) i = s.res[a] - 2;
    rp.i0[a] = i;
    rp.f[a] = idx - i;
  }
  return rp;
}

// out[rank_offset + r] = plane * line.
inline void RefProducts(const VmGrid& g, const RefPoint& rp, std::vector<double>* out) {
  out->clear();
  for (int m = 0; m < 3; ++m) {
    const int u = kMat[m][0], v = kMat[m][1], w = kVec[m];
    for (int r = 0; r < g.ranks[m]; ++r) {
      const double fu = rp.f[u], fv = rp.f[v], fw = rp.f[w];
      const int x = rp.i0[u], y = rp.i0[v], k = rp.i0[w];
      const double pl = GridPlane(g, m, y, x, r) * (1 - fu) * (1 - fv) +
                        GridPlane(g, m, y, x + 1, r) * fu * (1 - fv) +
                        GridPlane(g, m, y + 1, x, r) * (1 - fu) * fv +
                        GridPlane(g, m, y + 1, x + 1, r) * fu * fv;
      const double li = GridLine(g, m, k, r) * (1 - fw) + GridLine(g, m, k + 1, r) * fw;
      out->push_back(pl * li);
    }
  }
}

inline bool RefMaskKeeps(const OccupancyMask& mask, const float p[3]) {
  const int* res = mask.res();
  float idx[3];  // float, as grid_sample computes it
  for (int a = 0; a < 3; ++a) {
    const float inv = 1.0f / (mask.aabb_max()[a] - mask.aabb_min()[a]) * 2.f;
    const float c = (p[a] - mask.aabb_min()[a]) * inv - 1.f;
    idx[a] = (c + 1.f) / 2.f * float(res[a] - 1);
  }
  double value = 0.0;
  int i0[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    i0[a] = int(std::floor(idx[a]));
    f[a] = double(idx[a]) - i0[a];
  }
  for (int c = 0; c < 8; ++c) {
    const int x = i0[0] + (c & 1), y = i0[1] + ((c >> 1) & 1), z = i0[2] + (c >> 2);
    if (x < 0 || y < 0 || z < 0 || x >= res[0] || y >= res[1] || z >= res[2]) continue;
    const double w = ((c & 1) ? f[0] : 1 - f[0]) * (((c >> 1) & 1) ? f[1] : 1 - f[1]) *
                     ((c >> 2) ? f[2] : 1 - f[2]);
    value += w * (mask.Get(x, y, z) ? 1.0 : 0.0);
  }
  return value > 0.0;
}

inline void NaiveMlp(const MlpConfig& cfg, const std::vector<float>& params,
                     const std::vector<double>& prod, const float* vd, double rgb[3]) {
  const int P = cfg.num_products, F = cfg.feature_dim, H = cfg.hidden, in_dim = cfg.input_dim();
  const size_t H2 = cfg.hidden_layers == 2 ? size_t(H) : 0;  // no W2, b2 with one hidden layer
  const size_t o_w1 = size_t(F) * P, o_b1 = o_w1 + size_t(H) * in_dim, o_w2 = o_b1 + H,
               o_b2 = o_w2 + H2 * H2, o_w3 = o_b2 + H2, o_b3 = o_w3 + 3 * size_t(H);
  std::vector<double> feat(F, 0.0);
  for (int j = 0; j < F; ++j)
    for (int k = 0; k < P; ++k) feat[j] += double(params[size_t(j) * P + k]) * prod[k];
  if (H == 0) {  // spherical harmonics (7.6.2): the real basis, as Plenoxels and 3DGS sign it
    const double X = vd[0], Y = vd[1], Z = vd[2], pi = 3.14159265358979323846;
    const double c1 = std::sqrt(3 / (4 * pi)), c2 = std::sqrt(15 / pi) / 2,
                 c3 = std::sqrt(35 / (2 * pi)) / 4, c4 = std::sqrt(105 / pi) / 2,
                 c5 = std::sqrt(21 / (2 * pi)) / 4;
    const double basis[16] = {0.5 / std::sqrt(pi),
                              -c1 * Y,
                              c1 * Z,
                              -c1 * X,
                              c2 * X * Y,
                              -c2 * Y * Z,
                              std::sqrt(5 / pi) / 4 * (3 * Z * Z - 1),
                              -c2 * X * Z,
                              c2 / 2 * (X * X - Y * Y),
                              -c3 * Y * (3 * X * X - Y * Y),
                              c4 * X * Y * Z,
                              -c5 * Y * (5 * Z * Z - 1),
                              std::sqrt(7 / pi) / 4 * Z * (5 * Z * Z - 3),
                              -c5 * X * (5 * Z * Z - 1),
                              c4 / 2 * Z * (X * X - Y * Y),
                              -c3 * X * (X * X - 3 * Y * Y)};
    const int K = F / 3;
    for (int c = 0; c < 3; ++c) {
      double z = params[size_t(F) * P + c];  // b3: the only parameter after the basis
      for (int k = 0; k < K; ++k) z += basis[k] * feat[size_t(c) * K + k];
      rgb[c] = 1.0 / (1.0 + std::exp(-z));
    }
    return;
  }
  std::vector<double> x(feat);
  for (int c = 0; c < 3; ++c) x.push_back(vd[c]);
  auto pe = [&](const std::vector<double>& v, int freqs) {
    std::vector<double> args;
    for (double a : v)
      for (int q = 0; q < freqs; ++q) args.push_back(a * std::ldexp(1.0, q));
    for (double a : args) x.push_back(std::sin(a));
    for (double a : args) x.push_back(std::cos(a));
  };
  pe(feat, cfg.feature_pe_freqs);
  pe(std::vector<double>(vd, vd + 3), cfg.viewdir_pe_freqs);
  auto layer = [&](const std::vector<double>& a, size_t ow, size_t ob, int out, bool relu) {
    std::vector<double> y(out);
    for (int j = 0; j < out; ++j) {
      double s = params[ob + j];
      for (size_t k = 0; k < a.size(); ++k) s += double(params[ow + j * a.size() + k]) * a[k];
      y[j] = relu ? std::max(s, 0.0) : s;
    }
    return y;
  };
  std::vector<double> h = layer(x, o_w1, o_b1, H, true);
  if (cfg.hidden_layers == 2) h = layer(h, o_w2, o_b2, H, true);
  const std::vector<double> z = layer(h, o_w3, o_b3, 3, false);
  for (int c = 0; c < 3; ++c) rgb[c] = 1.0 / (1.0 + std::exp(-z[c]));
}

// Compositing of 7.2 / 7.5 in double, one sample at a time; `rp` null: a sample with sigma 0.
struct NaiveComposite {
  double T = 1.0, acc = 0.0, col[3] = {0, 0, 0};
  std::vector<double> prod;

  void Add(const TestScene& ts, const RefPoint* rp, double dist, const float d[3]) {
    const SceneField& s = ts.field;
    double sigma = 0.0;
    if (rp != nullptr) {
      RefProducts(s.density, *rp, &prod);
      double feat = 0.0;
      for (double v : prod) feat += v;
      const double x = feat + s.density_shift;
      sigma = s.density_activation == DensityActivation::kRelu ? std::max(x, 0.0)
              : x > 20.0                                       ? x
                                                               : std::log1p(std::exp(x));
    }
    const double alpha = 1.0 - std::exp(-sigma * dist * s.distance_scale);
    const double w = alpha * T;
    T *= 1.0 - alpha + 1e-10;
    acc += w;
    if (w > s.weight_threshold) {
      RefProducts(s.appearance, *rp, &prod);
      double c[3];
      NaiveMlp(s.mlp.config(), ts.mlp_params, prod, d, c);
      for (int k = 0; k < 3; ++k) col[k] += w * c[k];
    }
  }
  void Finish(const SceneField& s, double rgb[3], double* acc_out) const {
    for (int k = 0; k < 3; ++k)
      rgb[k] = std::min(std::max(col[k] + (1.0 - acc) * s.background[k], 0.0), 1.0);
    *acc_out = acc;
  }
};

inline void NaiveRender(const TestScene& ts, const float o[3], const float d[3], double rgb[3],
                        double* acc_out) {
  const SceneField& s = ts.field;
  const float step = s.StepSize();
  const int n = s.NumSamples();
  float tmin = -INFINITY;
  for (int a = 0; a < 3; ++a) {
    const float vec = d[a] == 0.f ? 1e-6f : d[a];
    tmin = std::max(tmin, std::min((s.aabb_max[a] - o[a]) / vec, (s.aabb_min[a] - o[a]) / vec));
  }
  const float t0 = std::min(std::max(tmin, s.near_far[0]), s.near_far[1]);
  std::vector<float> z(n);
  for (int i = 0; i < n; ++i) z[i] = t0 + step * float(i);
  NaiveComposite comp;
  for (int i = 0; i < n; ++i) {
    const float p[3] = {o[0] + d[0] * z[i], o[1] + d[1] * z[i], o[2] + d[2] * z[i]};
    bool valid = true;
    for (int a = 0; a < 3; ++a) valid = valid && !(s.aabb_min[a] > p[a] || p[a] > s.aabb_max[a]);
    if (valid && s.has_mask) valid = RefMaskKeeps(s.mask, p);
    const RefPoint rp = valid ? Locate(s, p) : RefPoint{};
    const double dist = i + 1 < n ? double(float(z[i + 1] - z[i])) : 0.0;
    comp.Add(ts, valid ? &rp : nullptr, dist, d);
  }
  comp.Finish(s, rgb, acc_out);
}

// SPEC.md 7.2.1 written out from the pseudo-code (not decoder/contraction.h): positions in
// binary32 as specified, compositing in double.
inline void NaiveRenderUnbounded(const TestScene& ts, const float o[3], const float d[3],
                                 double rgb[3], double* acc_out) {
  const SceneField& s = ts.field;
  float S[3];
  for (int a = 0; a < 3; ++a) S[a] = (1.f / (s.aabb_max[a] - s.aabb_min[a])) * 2.f;
  auto contract = [](float v) {
    return v >= -1.f && v <= 1.f ? v : (v > 0.f ? 2.f - 1.f / v : -2.f - 1.f / v);
  };
  NaiveComposite comp;
  float t = s.near_far[0];
  const int n = s.NumSamples();
  for (int i = 0; i < n; ++i) {
    float q[3], x[3];
    for (int a = 0; a < 3; ++a) {
      const float p = o[a] + d[a] * t;
      q[a] = (p - s.aabb_min[a]) * S[a] - 1.f;
      x[a] = contract(q[a]);
    }
    float sum = 0.f;
    for (int a = 0; a < 3; ++a) {
      const float qq = q[a] * q[a];
      const float g = d[a] * S[a] / (qq > 1.f ? qq : 1.f);
      sum = sum + g * g;
    }
    const float next = t + s.StepSize() / std::sqrt(sum);
    const bool last = i + 1 == n || !std::isfinite(next);
    const double dist = last ? 0.0 : double(next - t);
    if (!s.has_mask || RefMaskKeeps(s.mask, x)) {
      const RefPoint rp = Locate(s, x);
      comp.Add(ts, &rp, dist, d);
    }
    if (last) break;
    t = next;
  }
  comp.Finish(s, rgb, acc_out);
}

// ------------------------------------------------------------------------------------------
// Ray sets

inline void Normalize(float d[3]) {
  const float l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  for (int a = 0; a < 3; ++a) d[a] /= l;
}

struct Rays {
  std::vector<float> o, d;
  std::vector<const char*> kind;
  void Add(const float* oo, const float* dd, const char* k) {
    o.insert(o.end(), oo, oo + 3);
    d.insert(d.end(), dd, dd + 3);
    kind.push_back(k);
  }
  size_t size() const { return kind.size(); }
};

inline Rays MakeRays(const SceneField& s, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  std::normal_distribution<float> nrm(0.f, 1.f);
  Rays rays;
  auto in_box = [&](float frac_lo, float frac_hi, float p[3]) {
    for (int a = 0; a < 3; ++a) {
      const float f = frac_lo + (frac_hi - frac_lo) * u(rng);
      p[a] = s.aabb_min[a] + f * (s.aabb_max[a] - s.aabb_min[a]);
    }
  };
  // Camera-like rays from a sphere towards points in (or slightly around) the box.
  for (int i = 0; i < 160; ++i) {
    float o[3] = {nrm(rng), nrm(rng), nrm(rng)}, target[3], d[3];
    Normalize(o);
    for (float& v : o) v *= 3.5f;
    in_box(-0.1f, 1.1f, target);
    for (int a = 0; a < 3; ++a) d[a] = target[a] - o[a];
    Normalize(d);
    rays.Add(o, d, "camera");
  }
  // Axis-parallel rays (both signs), entering from outside through a random point of a face.
  for (int i = 0; i < 36; ++i) {
    const int axis = i % 3;
    const float sign = (i / 3) % 2 ? 1.f : -1.f;
    float o[3], d[3] = {0.f, 0.f, 0.f};
    in_box(0.02f, 0.98f, o);
    o[axis] = sign > 0 ? s.aabb_min[axis] - 0.7f : s.aabb_max[axis] + 0.7f;
    d[axis] = sign;
    rays.Add(o, d, "axis");
    // Same with a -0 component.
    float dz[3] = {d[0] == 0.f ? -0.f : d[0], d[1], d[2]};
    rays.Add(o, dz, "axis-negzero");
  }
  // Rays starting inside the box.
  for (int i = 0; i < 60; ++i) {
    float o[3], d[3] = {nrm(rng), nrm(rng), nrm(rng)};
    in_box(0.05f, 0.95f, o);
    Normalize(d);
    rays.Add(o, d, "inside");
  }
  // Rays missing the box: from outside, pointing away.
  for (int i = 0; i < 20; ++i) {
    float o[3] = {nrm(rng), nrm(rng), nrm(rng)};
    Normalize(o);
    for (float& v : o) v *= 4.f;
    float d[3] = {o[0] + 0.3f * nrm(rng), o[1] + 0.3f * nrm(rng), o[2] + 0.3f * nrm(rng)};
    Normalize(d);
    rays.Add(o, d, "miss");
  }
  // Grazing rays: within a face plane (d component 0, origin exactly on the face), along an
  // edge, and nearly tangent to a face.
  for (int i = 0; i < 24; ++i) {
    const int axis = i % 3;
    float o[3], d[3];
    in_box(0.1f, 0.9f, o);
    o[axis] = (i / 3) % 2 ? s.aabb_max[axis] : s.aabb_min[axis];
    const int b = (axis + 1) % 3, c = (axis + 2) % 3;
    d[axis] = 0.f;
    d[b] = nrm(rng);
    d[c] = nrm(rng);
    Normalize(d);
    const float back = 3.f;
    const float oo[3] = {o[0] - back * d[0], o[1] - back * d[1], o[2] - back * d[2]};
    float oo2[3] = {oo[0], oo[1], oo[2]};
    oo2[axis] = o[axis];  // keep exactly on the face plane
    rays.Add(oo2, d, "grazing-face");
    float dt[3] = {d[0], d[1], d[2]};
    dt[axis] = (o[axis] == s.aabb_max[axis] ? -1.f : 1.f) * 1e-4f;  // nearly tangent, into the box
    Normalize(dt);
    rays.Add(oo2, dt, "grazing-tilt");
  }
  // Along an edge of the box.
  {
    const float o[3] = {s.aabb_min[0] - 1.f, s.aabb_max[1], s.aabb_min[2]};
    const float d[3] = {1.f, 0.f, 0.f};
    rays.Add(o, d, "edge");
  }
  return rays;
}

}  // namespace naive
}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_NAIVE_RENDERER_H_
