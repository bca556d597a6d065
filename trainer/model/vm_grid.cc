#include "trainer/model/vm_grid.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

namespace ecrf {
namespace trainer {
namespace {

constexpr int64_t kParallelMin = 1 << 16;  // smaller loops stay on one thread

uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Standard normal for element k of stream seed (Box-Muller on two hashed uniforms).
float HashNormal(uint64_t seed, uint64_t k) {
  const uint64_t h1 = SplitMix64(seed * 0x2545F4914F6CDD1Dull + 2 * k);
  const uint64_t h2 = SplitMix64(seed * 0x2545F4914F6CDD1Dull + 2 * k + 1);
  const double u1 = (static_cast<double>(h1 >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  const double u2 = static_cast<double>(h2 >> 11) * (1.0 / 9007199254740992.0);
  return static_cast<float>(std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2));
}

template <int kR>
inline float DensityMode(const float* plane, int width, const float* line, int rank_rt, int x0,
                         int y0, int i0, float fu, float fv, float fw) {
  const int R = kR > 0 ? kR : rank_rt;
  const float* c00 = plane + (static_cast<size_t>(y0) * width + x0) * R;
  const float* c10 = c00 + R;
  const float* c01 = c00 + static_cast<size_t>(width) * R;
  const float* c11 = c01 + R;
  const float* l0 = line + static_cast<size_t>(i0) * R;
  const float* l1 = l0 + R;
  const float w00 = (1.f - fu) * (1.f - fv), w10 = fu * (1.f - fv);
  const float w01 = (1.f - fu) * fv, w11 = fu * fv;
  const float lw0 = 1.f - fw, lw1 = fw;
  float acc = 0.f;
#pragma omp simd reduction(+ : acc)
  for (int r = 0; r < R; ++r) {
    const float p = w00 * c00[r] + w10 * c10[r] + w01 * c01[r] + w11 * c11[r];
    const float l = lw0 * l0[r] + lw1 * l1[r];
    acc += p * l;
  }
  return acc;
}

template <int kR>
inline void ProductsMode(const float* plane, int width, const float* line, int rank_rt, int x0,
                         int y0, int i0, float fu, float fv, float fw, float* out) {
  const int R = kR > 0 ? kR : rank_rt;
  const float* c00 = plane + (static_cast<size_t>(y0) * width + x0) * R;
  const float* c10 = c00 + R;
  const float* c01 = c00 + static_cast<size_t>(width) * R;
  const float* c11 = c01 + R;
  const float* l0 = line + static_cast<size_t>(i0) * R;
  const float* l1 = l0 + R;
  const float w00 = (1.f - fu) * (1.f - fv), w10 = fu * (1.f - fv);
  const float w01 = (1.f - fu) * fv, w11 = fu * fv;
  const float lw0 = 1.f - fw, lw1 = fw;
#pragma omp simd
  for (int r = 0; r < R; ++r) {
    const float p = w00 * c00[r] + w10 * c10[r] + w01 * c01[r] + w11 * c11[r];
    const float l = lw0 * l0[r] + lw1 * l1[r];
    out[r] = p * l;
  }
}

// One interpolation step of F.interpolate(align_corners=True): source index of output j.
inline void SourceIndex(int in_size, int out_size, int j, int* i0, int* i1, float* lambda) {
  const float scale =
      out_size > 1 ? static_cast<float>(in_size - 1) / static_cast<float>(out_size - 1) : 0.f;
  const float src = scale * static_cast<float>(j);
  int i = static_cast<int>(src);
  if (i > in_size - 1) i = in_size - 1;
  *i0 = i;
  *i1 = i + (i < in_size - 1 ? 1 : 0);
  *lambda = src - static_cast<float>(i);
}

}  // namespace

void VmGrid::ComputeOffsets() {
  size_t off = 0;
  for (int m = 0; m < 3; ++m) {
    plane_off_[m] = off;
    off += plane_size(m);
  }
  for (int m = 0; m < 3; ++m) {
    line_off_[m] = off;
    off += line_size(m);
  }
}

void VmGrid::Allocate(const std::array<int, 3>& res, const std::array<int, 3>& ranks) {
  for (int a = 0; a < 3; ++a) {
    if (res[a] < 2) throw std::runtime_error("VmGrid: every resolution must be >= 2");
    if (ranks[a] < 1) throw std::runtime_error("VmGrid: every rank must be >= 1");
  }
  res_ = res;
  ranks_ = ranks;
  ComputeOffsets();
  const size_t total = line_off_[2] + line_size(2);
  params_.assign(total, 0.f);
  grads_.assign(total, 0.f);
}

std::vector<size_t> VmGrid::KeptIndices(const std::array<std::vector<uint8_t>, 3>& keep) const {
  for (int m = 0; m < 3; ++m) {
    if (keep[m].size() != static_cast<size_t>(ranks_[m])) {
      throw std::invalid_argument("VmGrid::KeptIndices: one flag per component expected");
    }
  }
  std::vector<size_t> idx;
  auto add = [&](size_t offset, size_t cells, int m) {
    for (size_t c = 0; c < cells; ++c) {
      for (int r = 0; r < ranks_[m]; ++r) {
        if (keep[m][r]) idx.push_back(offset + c * ranks_[m] + r);
      }
    }
  };
  for (int m = 0; m < 3; ++m) add(plane_off_[m], plane_size(m) / ranks_[m], m);
  for (int m = 0; m < 3; ++m) add(line_off_[m], line_size(m) / ranks_[m], m);
  return idx;
}

void VmGrid::KeepComponents(const std::array<std::vector<uint8_t>, 3>& keep) {
  std::array<int, 3> ranks{};
  for (int m = 0; m < 3; ++m) {
    ranks[m] = 0;
    for (uint8_t k : keep[m]) ranks[m] += k ? 1 : 0;
    if (ranks[m] < 1) throw std::invalid_argument("VmGrid::KeepComponents: a mode would be empty");
  }
  const std::vector<size_t> idx = KeptIndices(keep);
  std::vector<float> kept(idx.size());
  for (size_t i = 0; i < idx.size(); ++i) kept[i] = params_[idx[i]];
  Allocate(res_, ranks);
  params_ = std::move(kept);
}

void VmGrid::InitNormal(float scale, uint64_t seed) {
  const int64_t n = static_cast<int64_t>(params_.size());
  float* p = params_.data();
#pragma omp parallel for schedule(static) if (n > kParallelMin)
  for (int64_t k = 0; k < n; ++k) p[k] = scale * HashNormal(seed, static_cast<uint64_t>(k));
}

void VmGrid::ZeroGrads() {
  const int64_t n = static_cast<int64_t>(grads_.size());
  float* g = grads_.data();
#pragma omp parallel for schedule(static) if (n > kParallelMin)
  for (int64_t k = 0; k < n; ++k) g[k] = 0.f;
}

float VmGrid::Density(const GridPoint& gp) const {
  float acc = 0.f;
  for (int m = 0; m < 3; ++m) {
    const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
    const int R = ranks_[m];
    const float* pl = params_.data() + plane_off_[m];
    const float* ln = params_.data() + line_off_[m];
    switch (R) {
      case 16:
        acc += DensityMode<16>(pl, res_[u], ln, R, gp.i0[u], gp.i0[v], gp.i0[w], gp.f[u], gp.f[v],
                               gp.f[w]);
        break;
      case 8:
        acc += DensityMode<8>(pl, res_[u], ln, R, gp.i0[u], gp.i0[v], gp.i0[w], gp.f[u], gp.f[v],
                              gp.f[w]);
        break;
      default:
        acc += DensityMode<0>(pl, res_[u], ln, R, gp.i0[u], gp.i0[v], gp.i0[w], gp.f[u], gp.f[v],
                              gp.f[w]);
    }
  }
  return acc;
}

void VmGrid::Products(const GridPoint& gp, float* out) const {
  int off = 0;
  for (int m = 0; m < 3; ++m) {
    const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
    const int R = ranks_[m];
    const float* pl = params_.data() + plane_off_[m];
    const float* ln = params_.data() + line_off_[m];
    switch (R) {
      case 48:
        ProductsMode<48>(pl, res_[u], ln, R, gp.i0[u], gp.i0[v], gp.i0[w], gp.f[u], gp.f[v],
                         gp.f[w], out + off);
        break;
      case 16:
        ProductsMode<16>(pl, res_[u], ln, R, gp.i0[u], gp.i0[v], gp.i0[w], gp.f[u], gp.f[v],
                         gp.f[w], out + off);
        break;
      default:
        ProductsMode<0>(pl, res_[u], ln, R, gp.i0[u], gp.i0[v], gp.i0[w], gp.f[u], gp.f[v], gp.f[w],
                        out + off);
    }
    off += R;
  }
}

void VmGrid::Prefetch(const GridPoint& gp, bool for_write) const {
  for (int m = 0; m < 3; ++m) PrefetchMode(gp, m, for_write);
}

void VmGrid::PrefetchMode(const GridPoint& gp, int m, bool for_write) const {
  const float* base = for_write ? grads_.data() : params_.data();
  const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
  const int R = ranks_[m];
  const int W = res_[u];
  const float* c00 = base + plane_off_[m] + (static_cast<size_t>(gp.i0[v]) * W + gp.i0[u]) * R;
  const float* c01 = c00 + static_cast<size_t>(W) * R;
  const float* l0 = base + line_off_[m] + static_cast<size_t>(gp.i0[w]) * R;
  for (int k = 0; k < 2 * R; k += 16) {
    if (for_write) {
      __builtin_prefetch(c00 + k, 1);
      __builtin_prefetch(c01 + k, 1);
      __builtin_prefetch(l0 + k, 1);
    } else {
      __builtin_prefetch(c00 + k);
      __builtin_prefetch(c01 + k);
      __builtin_prefetch(l0 + k);
    }
  }
}

void VmGrid::UpsampleTo(const std::array<int, 3>& new_res) {
  for (int a = 0; a < 3; ++a)
    if (new_res[a] < 2) throw std::runtime_error("VmGrid::UpsampleTo: resolution must be >= 2");
  VmGrid out;
  out.Allocate(new_res, ranks_);
  for (int m = 0; m < 3; ++m) {
    const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
    const int R = ranks_[m];
    const int H = res_[v], W = res_[u], H2 = new_res[v], W2 = new_res[u];
    const float* src = plane(m);
    float* dst = out.plane(m);
#pragma omp parallel for schedule(static) if (static_cast <int64_t>(H2) * W2 * R > kParallelMin)
    for (int y = 0; y < H2; ++y) {
      int y0, y1;
      float ly;
      SourceIndex(H, H2, y, &y0, &y1, &ly);
      for (int x = 0; x < W2; ++x) {
        int x0, x1;
        float lx;
        SourceIndex(W, W2, x, &x0, &x1, &lx);
        const float* a00 = src + (static_cast<size_t>(y0) * W + x0) * R;
        const float* a01 = src + (static_cast<size_t>(y0) * W + x1) * R;
        const float* a10 = src + (static_cast<size_t>(y1) * W + x0) * R;
        const float* a11 = src + (static_cast<size_t>(y1) * W + x1) * R;
        float* o = dst + (static_cast<size_t>(y) * W2 + x) * R;
        for (int r = 0; r < R; ++r)
          o[r] = (1.f - ly) * ((1.f - lx) * a00[r] + lx * a01[r]) +
                 ly * ((1.f - lx) * a10[r] + lx * a11[r]);
      }
    }
    const int L = res_[w], L2 = new_res[w];
    const float* lsrc = line(m);
    float* ldst = out.line(m);
    for (int i = 0; i < L2; ++i) {
      int i0, i1;
      float li;
      SourceIndex(L, L2, i, &i0, &i1, &li);
      for (int r = 0; r < R; ++r)
        ldst[static_cast<size_t>(i) * R + r] = (1.f - li) * lsrc[static_cast<size_t>(i0) * R + r] +
                                               li * lsrc[static_cast<size_t>(i1) * R + r];
    }
  }
  *this = std::move(out);
}

void VmGrid::Crop(const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
  std::array<int, 3> new_res;
  for (int a = 0; a < 3; ++a) {
    if (lo[a] < 0 || hi[a] > res_[a] || hi[a] - lo[a] < 2)
      throw std::runtime_error("VmGrid::Crop: invalid range on axis " + std::to_string(a) + ": [" +
                               std::to_string(lo[a]) + ", " + std::to_string(hi[a]) + ") of " +
                               std::to_string(res_[a]));
    new_res[a] = hi[a] - lo[a];
  }
  VmGrid out;
  out.Allocate(new_res, ranks_);
  for (int m = 0; m < 3; ++m) {
    const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
    const int R = ranks_[m];
    const int W = res_[u], W2 = new_res[u];
    for (int y = 0; y < new_res[v]; ++y) {
      const float* s = plane(m) + (static_cast<size_t>(y + lo[v]) * W + lo[u]) * R;
      float* d = out.plane(m) + static_cast<size_t>(y) * W2 * R;
      std::memcpy(d, s, sizeof(float) * static_cast<size_t>(W2) * R);
    }
    std::memcpy(out.line(m), line(m) + static_cast<size_t>(lo[w]) * R,
                sizeof(float) * static_cast<size_t>(new_res[w]) * R);
  }
  *this = std::move(out);
}

double VmGrid::L1(float weight) {
  double total = 0.0;
  for (int t = 0; t < 6; ++t) {
    const int m = t % 3;
    const size_t off = t < 3 ? plane_off_[m] : line_off_[m];
    const int64_t n = static_cast<int64_t>(t < 3 ? plane_size(m) : line_size(m));
    const float* p = params_.data() + off;
    float* g = grads_.data() + off;
    const float coef = weight / static_cast<float>(n);
    double sum = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : sum) if (n > kParallelMin)
    for (int64_t k = 0; k < n; ++k) {
      const float x = p[k];
      sum += std::fabs(x);
      g[k] += x > 0.f ? coef : (x < 0.f ? -coef : 0.f);
    }
    total += sum / static_cast<double>(n);
  }
  return total;
}

double VmGrid::PlaneTotalVariation(float weight) {
  constexpr double kPlaneFactor = 1e-2;  // TensoRF's per-plane factor
  double total = 0.0;
  for (int m = 0; m < 3; ++m) {
    const int w = res_[kMatMode[m][0]], h = res_[kMatMode[m][1]], c = ranks_[m];
    if (w < 2 || h < 2 || c < 1) continue;
    const int64_t row = static_cast<int64_t>(w) * c;
    const double count_v = static_cast<double>(h - 1) * row;
    const double count_u = static_cast<double>(h) * (w - 1) * c;
    // d(loss)/d(difference) = 2 * difference * these.
    const float cv = static_cast<float>(weight * kPlaneFactor * 2.0 / count_v * 2.0);
    const float cu = static_cast<float>(weight * kPlaneFactor * 2.0 / count_u * 2.0);
    const float* p = plane(m);
    float* g = plane_grad(m);
    double sum_v = 0.0, sum_u = 0.0;
    // Each row writes only its own gradients (the differences to both neighbours are recomputed),
    // so rows run in parallel with the same sums for any thread count.
#pragma omp parallel for schedule(static) reduction(+ : sum_v, sum_u) \
    if (static_cast<int64_t>(h) * row > kParallelMin)
    for (int y = 0; y < h; ++y) {
      const float* r = p + y * row;
      float* gr = g + y * row;
      for (int64_t k = 0; k < row; ++k) {
        float grad = 0.f;
        if (y + 1 < h) {
          const float d = r[k + row] - r[k];
          sum_v += static_cast<double>(d) * d;
          grad -= cv * d;
        }
        if (y > 0) grad += cv * (r[k] - r[k - row]);
        if (k + c < row) {
          const float d = r[k + c] - r[k];
          sum_u += static_cast<double>(d) * d;
          grad -= cu * d;
        }
        if (k >= c) grad += cu * (r[k] - r[k - c]);
        gr[k] += grad;
      }
    }
    total += kPlaneFactor * 2.0 * (sum_v / count_v + sum_u / count_u);
  }
  return total;
}

// ---------------------------------------------------------------------------------------------
// ModeGradScatter

void ModeGradScatter::Bind(VmGrid* grid, int mode) {
  BindTile(grid, mode, 0, grid->res()[kMatMode[mode][0]], 0, grid->res()[kMatMode[mode][1]],
           grid->line_grad(mode));
}

void ModeGradScatter::BindTile(VmGrid* grid, int mode, int x0, int x1, int y0, int y1,
                               float* line_out) {
  grid_ = grid;
  mode_ = mode;
  rank_ = grid->ranks()[mode];
  x0_ = x0;
  x1_ = x1;
  y0_ = y0;
  y1_ = y1;
  line_out_ = line_out;
  for (int s = 0; s < 16; ++s) plane_key_[s] = -1;
  for (int s = 0; s < 4; ++s) line_key_[s] = -1;
  plane_acc_.assign(static_cast<size_t>(16) * rank_, 0.f);
  line_acc_.assign(static_cast<size_t>(4) * rank_, 0.f);
  tmp_.assign(static_cast<size_t>(2) * rank_, 0.f);
}

namespace {
inline void AddAndClear(float* __restrict dst, float* __restrict acc, int n) {
#pragma omp simd
  for (int r = 0; r < n; ++r) {
    dst[r] += acc[r];
    acc[r] = 0.f;
  }
}
}  // namespace

void ModeGradScatter::FlushPlaneSlot(int s) {
  AddAndClear(grid_->plane_grad(mode_) + static_cast<size_t>(plane_key_[s]) * rank_,
              plane_acc_.data() + static_cast<size_t>(s) * rank_, rank_);
  plane_key_[s] = -1;
}

void ModeGradScatter::FlushLineSlot(int s) {
  AddAndClear(line_out_ + static_cast<size_t>(line_key_[s]) * rank_,
              line_acc_.data() + static_cast<size_t>(s) * rank_, rank_);
  line_key_[s] = -1;
}

void ModeGradScatter::Flush() {
  for (int s = 0; s < 16; ++s)
    if (plane_key_[s] >= 0) FlushPlaneSlot(s);
  for (int s = 0; s < 4; ++s)
    if (line_key_[s] >= 0) FlushLineSlot(s);
}

template <bool kDensity, int kR>
void ModeGradScatter::Add(const GridPoint& gp, float g_scalar, const float* g_mode) {
  const int m = mode_;
  const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
  const int R = kR > 0 ? kR : rank_;
  const int W = grid_->res()[u];
  const int x0 = gp.i0[u], y0 = gp.i0[v], i0 = gp.i0[w];
  const float fu = gp.f[u], fv = gp.f[v], fw = gp.f[w];
  const float* c00 = grid_->plane(m) + (static_cast<size_t>(y0) * W + x0) * R;
  const float* c10 = c00 + R;
  const float* c01 = c00 + static_cast<size_t>(W) * R;
  const float* c11 = c01 + R;
  const float* l0 = grid_->line(m) + static_cast<size_t>(i0) * R;
  const float* l1 = l0 + R;
  const float cw[4] = {(1.f - fu) * (1.f - fv), fu * (1.f - fv), (1.f - fu) * fv, fu * fv};
  const float lw[2] = {1.f - fw, fw};
  // dp[r] = dL/d(plane value r) = g_r * l[r];  dl[r] = dL/d(line value r) = g_r * p[r].
  float* __restrict dp = tmp_.data();
  float* __restrict dl = tmp_.data() + R;
#pragma omp simd
  for (int r = 0; r < R; ++r) {
    const float p = cw[0] * c00[r] + cw[1] * c10[r] + cw[2] * c01[r] + cw[3] * c11[r];
    const float l = lw[0] * l0[r] + lw[1] * l1[r];
    const float g = kDensity ? g_scalar : g_scalar * g_mode[r];
    dp[r] = g * l;
    dl[r] = g * p;
  }
  for (int c = 0; c < 4; ++c) {
    const float wc = cw[c];
    if (wc == 0.f) continue;
    const int x = x0 + (c & 1), y = y0 + (c >> 1);
    if (x < x0_ || x >= x1_ || y < y0_ || y >= y1_) continue;  // another tile's vertex
    const int s = (x & 3) | ((y & 3) << 2);
    const int key = y * W + x;
    if (plane_key_[s] != key) {
      if (plane_key_[s] >= 0) FlushPlaneSlot(s);
      plane_key_[s] = key;
    }
    float* __restrict acc = plane_acc_.data() + static_cast<size_t>(s) * R;
#pragma omp simd
    for (int r = 0; r < R; ++r) acc[r] += wc * dp[r];
  }
  // The line part once per sample: in the tile of the sample's lower corner.
  if (x0 < x0_ || x0 >= x1_ || y0 < y0_ || y0 >= y1_) return;
  for (int c = 0; c < 2; ++c) {
    const float wc = lw[c];
    if (wc == 0.f) continue;
    const int i = i0 + c;
    const int s = i & 3;
    if (line_key_[s] != i) {
      if (line_key_[s] >= 0) FlushLineSlot(s);
      line_key_[s] = i;
    }
    float* __restrict acc = line_acc_.data() + static_cast<size_t>(s) * R;
#pragma omp simd
    for (int r = 0; r < R; ++r) acc[r] += wc * dl[r];
  }
}

template <bool kDensity>
void ModeGradScatter::Dispatch(const GridPoint& gp, float g_scalar, const float* g_mode) {
  switch (rank_) {
    case 16:
      Add<kDensity, 16>(gp, g_scalar, g_mode);
      break;
    case 48:
      Add<kDensity, 48>(gp, g_scalar, g_mode);
      break;
    default:
      Add<kDensity, 0>(gp, g_scalar, g_mode);
  }
}

void ModeGradScatter::AddDensity(const GridPoint& gp, float g) { Dispatch<true>(gp, g, nullptr); }

void ModeGradScatter::AddProducts(const GridPoint& gp, const float* g, float scale) {
  Dispatch<false>(gp, scale, g);
}

}  // namespace trainer
}  // namespace ecrf
