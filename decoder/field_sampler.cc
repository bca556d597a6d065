#include "decoder/field_sampler.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>

#include "decoder/contraction.h"

namespace ecrf {
namespace dec {
namespace {

// Per-mode corner pointers and weights for one grid point.
template <typename T>
struct ModeTaps {
  const T* p00;  // plane (u0, v0)
  const T* p01;  // (u0+1, v0)
  const T* p10;  // (u0, v0+1)
  const T* p11;
  const T* l0;
  const T* l1;
  float fu, fv, fw, scale;
};

template <typename T>
inline const T* PlaneData(const VmGrid& g, int m);
template <>
inline const float* PlaneData<float>(const VmGrid& g, int m) {
  return g.plane_f32[m].data();
}
template <>
inline const int16_t* PlaneData<int16_t>(const VmGrid& g, int m) {
  return g.plane_i16[m].data();
}
template <typename T>
inline const T* LineData(const VmGrid& g, int m);
template <>
inline const float* LineData<float>(const VmGrid& g, int m) {
  return g.line_f32[m].data();
}
template <>
inline const int16_t* LineData<int16_t>(const VmGrid& g, int m) {
  return g.line_i16[m].data();
}

template <typename T>
inline ModeTaps<T> Taps(const VmGrid& g, const GridPoint& gp, int m) {
  const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
  const int R = g.ranks[m];
  const size_t ru = static_cast<size_t>(g.res[u]);
  ModeTaps<T> t;
  t.p00 = PlaneData<T>(g, m) + (static_cast<size_t>(gp.i0[v]) * ru + gp.i0[u]) * R;
  t.p01 = t.p00 + R;
  t.p10 = t.p00 + ru * R;
  t.p11 = t.p10 + R;
  t.l0 = LineData<T>(g, m) + static_cast<size_t>(gp.i0[w]) * R;
  t.l1 = t.l0 + R;
  t.fu = gp.f[u];
  t.fv = gp.f[v];
  t.fw = gp.f[w];
  t.scale = std::is_same<T, float>::value ? 1.f : g.plane_scale[m] * g.line_scale[m];
  return t;
}

template <typename T>
float DensityFeatureT(const VmGrid& g, const GridPoint& gp) {
  float total = 0.f;
  for (int m = 0; m < 3; ++m) {
    const int R = g.ranks[m];
    if (R == 0) continue;
    const ModeTaps<T> t = Taps<T>(g, gp, m);
    const float w00 = (1.f - t.fu) * (1.f - t.fv), w01 = t.fu * (1.f - t.fv);
    const float w10 = (1.f - t.fu) * t.fv, w11 = t.fu * t.fv;
    const float wl0 = 1.f - t.fw, wl1 = t.fw;
    float sum = 0.f;
    for (int r = 0; r < R; ++r) {
      const float p = w00 * static_cast<float>(t.p00[r]) + w01 * static_cast<float>(t.p01[r]) +
                      w10 * static_cast<float>(t.p10[r]) + w11 * static_cast<float>(t.p11[r]);
      const float l = wl0 * static_cast<float>(t.l0[r]) + wl1 * static_cast<float>(t.l1[r]);
      sum += p * l;
    }
    total += sum * t.scale;
  }
  return total;
}

// kAccumulate: out[k] += weight * product (the deferred head's weighted sum, 7.6, rounded as the
// product's own value times the weight), else out[k] = product.
template <typename T, bool kAccumulate>
void AppearanceProductsT(const VmGrid& g, const GridPoint& gp, float weight, float* out) {
  for (int m = 0; m < 3; ++m) {
    const int R = g.ranks[m];
    if (R == 0) continue;
    const ModeTaps<T> t = Taps<T>(g, gp, m);
    const float w00 = (1.f - t.fu) * (1.f - t.fv) * t.scale, w01 = t.fu * (1.f - t.fv) * t.scale;
    const float w10 = (1.f - t.fu) * t.fv * t.scale, w11 = t.fu * t.fv * t.scale;
    const float wl0 = 1.f - t.fw, wl1 = t.fw;
    float* o = out + g.rank_offset(m);
    for (int r = 0; r < R; ++r) {
      const float p = w00 * static_cast<float>(t.p00[r]) + w01 * static_cast<float>(t.p01[r]) +
                      w10 * static_cast<float>(t.p10[r]) + w11 * static_cast<float>(t.p11[r]);
      const float l = wl0 * static_cast<float>(t.l0[r]) + wl1 * static_cast<float>(t.l1[r]);
      if (kAccumulate) {
        o[r] += weight * (p * l);
      } else {
        o[r] = p * l;
      }
    }
  }
}

bool AllFinite(const float* p, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(p[i])) return false;
  }
  return true;
}

}  // namespace

float DensityFeature(const VmGrid& grid, const GridPoint& gp) {
  return grid.storage == GridStorage::kInt16 ? DensityFeatureT<int16_t>(grid, gp)
                                             : DensityFeatureT<float>(grid, gp);
}

void AppearanceProducts(const VmGrid& grid, const GridPoint& gp, float* out) {
  if (grid.storage == GridStorage::kInt16) {
    AppearanceProductsT<int16_t, false>(grid, gp, 0.f, out);
  } else {
    AppearanceProductsT<float, false>(grid, gp, 0.f, out);
  }
}

void AccumulateAppearanceProducts(const VmGrid& grid, const GridPoint& gp, float weight,
                                  float* sum) {
  if (grid.storage == GridStorage::kInt16) {
    AppearanceProductsT<int16_t, true>(grid, gp, weight, sum);
  } else {
    AppearanceProductsT<float, true>(grid, gp, weight, sum);
  }
}

Status QuantizeGridInt16(const VmGrid& src, VmGrid* dst) {
  ECRF_CHECK_OR_RETURN(dst != nullptr && dst != &src && src.storage == GridStorage::kFloat32,
                       kErrInvalidArgument, "QuantizeGridInt16: needs a float32 source");
  ECRF_RETURN_IF_ERROR(src.Validate("source"));
  ECRF_RETURN_IF_ERROR(dst->Allocate(src.res, src.ranks, GridStorage::kInt16));
  auto quantize = [](const float* in, size_t n, int16_t* out, float* scale) {
    float mx = 0.f;
    for (size_t i = 0; i < n; ++i) mx = std::max(mx, std::fabs(in[i]));
    *scale = mx > 0.f ? mx / 32767.f : 1.f;
    const float inv = 1.f / *scale;
    for (size_t i = 0; i < n; ++i) {
      float q = std::nearbyint(in[i] * inv);
      q = q > 32767.f ? 32767.f : (q < -32767.f ? -32767.f : q);
      out[i] = static_cast<int16_t>(q);
    }
  };
  for (int m = 0; m < 3; ++m) {
    quantize(src.plane_f32[m].data(), src.plane_count(m), dst->plane_i16[m].data(),
             &dst->plane_scale[m]);
    quantize(src.line_f32[m].data(), src.line_count(m), dst->line_i16[m].data(),
             &dst->line_scale[m]);
  }
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// VmGrid

Status VmGrid::Allocate(const int res_in[3], const int ranks_in[3], GridStorage storage_in) {
  for (int a = 0; a < 3; ++a) {
    ECRF_CHECK_OR_RETURN(res_in[a] >= 2 && res_in[a] <= kMaxGridRes, kErrLimit,
                         "grid resolution %d on axis %d out of range [2, %d]", res_in[a], a,
                         kMaxGridRes);
    ECRF_CHECK_OR_RETURN(ranks_in[a] >= 0 && ranks_in[a] <= kMaxRank, kErrLimit,
                         "grid rank %d of mode %d out of range [0, %d]", ranks_in[a], a, kMaxRank);
  }
  ECRF_CHECK_OR_RETURN(storage_in == GridStorage::kFloat32 || storage_in == GridStorage::kInt16,
                       kErrUnsupported, "unknown grid storage %d", static_cast<int>(storage_in));
  for (int a = 0; a < 3; ++a) {
    res[a] = res_in[a];
    ranks[a] = ranks_in[a];
    plane_scale[a] = line_scale[a] = 1.f;
    plane_f32[a].Reset();
    line_f32[a].Reset();
    plane_i16[a].Reset();
    line_i16[a].Reset();
  }
  storage = storage_in;
  for (int m = 0; m < 3; ++m) {
    size_t pc = 0, lc = 0;
    ECRF_CHECK_OR_RETURN(
        CheckedMul(static_cast<size_t>(res[kMatMode[m][1]]),
                   static_cast<size_t>(res[kMatMode[m][0]]), &pc) &&
            CheckedMul(pc, static_cast<size_t>(ranks[m]), &pc) &&
            CheckedMul(static_cast<size_t>(res[kVecMode[m]]), static_cast<size_t>(ranks[m]), &lc),
        kErrLimit, "grid mode %d size overflows", m);
    if (storage == GridStorage::kFloat32) {
      ECRF_RETURN_IF_ERROR(plane_f32[m].Allocate(pc));
      ECRF_RETURN_IF_ERROR(line_f32[m].Allocate(lc));
    } else {
      ECRF_RETURN_IF_ERROR(plane_i16[m].Allocate(pc));
      ECRF_RETURN_IF_ERROR(line_i16[m].Allocate(lc));
    }
  }
  return Status::Ok();
}

Status VmGrid::Validate(const char* what, bool check_values) const {
  for (int m = 0; m < 3; ++m) {
    ECRF_CHECK_OR_RETURN(
        res[m] >= 2 && res[m] <= kMaxGridRes && ranks[m] >= 0 && ranks[m] <= kMaxRank,
        kErrInvalidArgument, "%s grid: bad shape on axis/mode %d", what, m);
  }
  for (int m = 0; m < 3; ++m) {
    const size_t pc = plane_count(m), lc = line_count(m);
    if (storage == GridStorage::kFloat32) {
      ECRF_CHECK_OR_RETURN(plane_f32[m].size() == pc && line_f32[m].size() == lc,
                           kErrInvalidArgument, "%s grid: mode %d tensors not allocated", what, m);
      ECRF_CHECK_OR_RETURN(!check_values || (AllFinite(plane_f32[m].data(), pc) &&
                                             AllFinite(line_f32[m].data(), lc)),
                           kErrCorrupt, "%s grid: mode %d has non-finite values", what, m);
    } else if (storage == GridStorage::kInt16) {
      ECRF_CHECK_OR_RETURN(plane_i16[m].size() == pc && line_i16[m].size() == lc,
                           kErrInvalidArgument, "%s grid: mode %d tensors not allocated", what, m);
      ECRF_CHECK_OR_RETURN(std::isfinite(plane_scale[m]) && std::isfinite(line_scale[m]) &&
                               std::isfinite(plane_scale[m] * line_scale[m]),
                           kErrCorrupt, "%s grid: mode %d has a non-finite scale", what, m);
    } else {
      return Status::Error(kErrUnsupported, "%s grid: unknown storage", what);
    }
  }
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// OccupancyMask

Status OccupancyMask::Init(const float aabb_min[3], const float aabb_max[3], const int res[3]) {
  accel_ready_ = false;
  occupied_ = 0;
  for (int a = 0; a < 3; ++a) {
    ECRF_CHECK_OR_RETURN(res[a] >= 2 && res[a] <= kMaxGridRes, kErrLimit,
                         "alpha mask resolution %d on axis %d out of range [2, %d]", res[a], a,
                         kMaxGridRes);
    ECRF_CHECK_OR_RETURN(
        std::isfinite(aabb_min[a]) && std::isfinite(aabb_max[a]) && aabb_max[a] > aabb_min[a],
        kErrInvalidArgument, "alpha mask: empty or non-finite aabb on axis %d", a);
    min_[a] = aabb_min[a];
    max_[a] = aabb_max[a];
    inv_size_[a] = 1.0f / (aabb_max[a] - aabb_min[a]) * 2.f;
    res_[a] = res[a];
  }
  const size_t voxels = voxel_count();  // <= 4096^3 = 2^36: fits size_t on 64-bit
  ECRF_CHECK_OR_RETURN(voxels / res[0] / res[1] == static_cast<size_t>(res[2]), kErrLimit,
                       "alpha mask size overflows");
  ECRF_RETURN_IF_ERROR(bits_.Allocate((voxels + 7) / 8));
  for (int l = 0; l < kLevels; ++l) blocks_[l].Reset();
  return Status::Ok();
}

Status OccupancyMask::BuildAcceleration() {
  ECRF_CHECK_OR_RETURN(!bits_.empty(), kErrInvalidArgument, "alpha mask not initialised");
  accel_ready_ = false;
  for (int l = 0; l < kLevels; ++l) {
    size_t count = 1;
    for (int a = 0; a < 3; ++a) {
      dims_[l][a] = (res_[a] - 1 + kBlock[l] - 1) / kBlock[l];
      count *= static_cast<size_t>(dims_[l][a]);
    }
    ECRF_RETURN_IF_ERROR(blocks_[l].Allocate(count));
  }
  occupied_ = 0;
  // Only set voxels do work: zero bytes are skipped eight at a time, so an empty mask costs about
  // what its decode is charged (one unit per 64 voxels, SPEC.md 8) instead of a visit per voxel.
  const uint8_t* bytes = bits_.data();
  const size_t nbytes = bits_.size();
  const size_t X = static_cast<size_t>(res_[0]), XY = X * static_cast<size_t>(res_[1]);
  const size_t voxels = voxel_count();
  for (size_t at = 0; at < nbytes; at += 8) {
    const size_t n = std::min<size_t>(8, nbytes - at);
    uint64_t group = 0;
    std::memcpy(&group, bytes + at, n);
    if (group == 0) continue;
    for (size_t k = at; k < at + n; ++k) {
      for (unsigned bit = 0, byte = bytes[k]; byte != 0; ++bit, byte >>= 1) {
        if (!(byte & 1u)) continue;
        const size_t v = k * 8 + bit;
        if (v >= voxels) break;  // padding bits of the last byte
        ++occupied_;
        MarkBlocks(static_cast<int>(v % X), static_cast<int>(v / X % res_[1]),
                   static_cast<int>(v / XY));
      }
    }
  }
  // The coarsest level from the next: the closed range of a coarse block is the union of those of
  // the fine blocks inside it (a corner on a coarse boundary is in the last fine block before it),
  // so it is marked exactly when one of them is; one visit per fine block.
  static_assert(kBlock[0] == 4 * kBlock[1], "the coarsest level pools 4^3 blocks of the next");
  for (int bz = 0; bz < dims_[1][2]; ++bz)
    for (int by = 0; by < dims_[1][1]; ++by)
      for (int bx = 0; bx < dims_[1][0]; ++bx)
        if (blocks_[1][(static_cast<size_t>(bz) * dims_[1][1] + by) * dims_[1][0] + bx] != 0)
          blocks_[0][(static_cast<size_t>(bz >> 2) * dims_[0][1] + (by >> 2)) * dims_[0][0] +
                     (bx >> 2)] = 1;
  ECRF_RETURN_IF_ERROR(BuildEmptyRadius());
  accel_ready_ = true;
  return Status::Ok();
}

// The chessboard distance d from each finest block to the nearest occupied one, capped at
// C = kEmptyRadiusCap + 1, is separable: the distance along x, then the minimum over |dy| < C of
// max(|dy|, that), then the same over z. Windows of C - 1 blocks give exactly min(d, C): a nearer
// occupied block is inside the window, and every window holds the block's own capped value.
// radius = d - 1. A line of blocks that are all at the cap stays there in one pass, so empty
// space costs a few operations a block; at most about 2C + 4 a block on at most kMaxRadiusBlocks
// blocks otherwise (uncharged, like the 64^3 level: bounded whatever the stream, SPEC.md 8.1).
Status OccupancyMask::BuildEmptyRadius() {
  constexpr int L = kLevels - 1, W = kEmptyRadiusCap, C = kEmptyRadiusCap + 1;
  const int X = dims_[L][0], Y = dims_[L][1], Z = dims_[L][2];
  const size_t n = static_cast<size_t>(X) * Y * Z;
  radius_.Reset();
  if (n > kMaxRadiusBlocks) return Status::Ok();
  ECRF_RETURN_IF_ERROR(radius_.Allocate(n));
  uint8_t* d = radius_.data();  // the capped distance, then the radius
  const uint8_t* occupied = blocks_[L].data();
  for (size_t row = 0; row < static_cast<size_t>(Y) * Z; ++row) {
    const uint8_t* o = occupied + row * X;
    uint8_t* g = d + row * X;
    int run = C;
    for (int x = 0; x < X; ++x) g[x] = static_cast<uint8_t>(run = o[x] ? 0 : std::min(run + 1, C));
    run = C;
    for (int x = X - 1; x >= 0; --x) {
      run = o[x] ? 0 : std::min(run + 1, C);
      g[x] = static_cast<uint8_t>(std::min<int>(g[x], run));
    }
  }
  // One window pass along a line of `len` blocks `stride` apart, in place through a copy.
  uint8_t line[kMaxGridRes / 4 + 2];
  auto window = [&line](uint8_t* at, int len, size_t stride) {
    bool capped = true;
    for (int i = 0; i < len; ++i) {
      line[i] = at[static_cast<size_t>(i) * stride];
      capped = capped && line[i] == C;
    }
    if (capped) return;
    for (int i = 0; i < len; ++i) {
      int best = line[i];
      for (int s = 1; s <= W && s < best; ++s) {
        if (i - s >= 0) best = std::min(best, std::max(s, int{line[i - s]}));
        if (i + s < len) best = std::min(best, std::max(s, int{line[i + s]}));
      }
      at[static_cast<size_t>(i) * stride] = static_cast<uint8_t>(best);
    }
  };
  const size_t XY = static_cast<size_t>(X) * Y;
  for (int z = 0; z < Z; ++z)
    for (int x = 0; x < X; ++x) window(d + z * XY + x, Y, static_cast<size_t>(X));
  for (size_t xy = 0; xy < XY; ++xy) window(d + xy, Z, XY);
  for (size_t i = 0; i < n; ++i) d[i] = static_cast<uint8_t>(d[i] == 0 ? 0 : d[i] - 1);
  return Status::Ok();
}

void OccupancyMask::MarkBlocks(int x, int y, int z) {
  const int c[3] = {x, y, z};
  for (int l = 1; l < kLevels; ++l) {
    const int B = kBlock[l];
    // A corner on a block boundary belongs to the closed ranges of both blocks.
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      hi[a] = c[a] / B;
      lo[a] = (c[a] % B == 0 && c[a] > 0) ? hi[a] - 1 : hi[a];
      if (hi[a] > dims_[l][a] - 1) hi[a] = dims_[l][a] - 1;
    }
    for (int bz = lo[2]; bz <= hi[2]; ++bz)
      for (int by = lo[1]; by <= hi[1]; ++by)
        for (int bx = lo[0]; bx <= hi[0]; ++bx)
          blocks_[l][(static_cast<size_t>(bz) * dims_[l][1] + by) * dims_[l][0] + bx] = 1;
  }
}

// ---------------------------------------------------------------------------------------------
// SceneField

float SceneField::StepSize() const {
  if (step_size > 0.f) return step_size;
  float mean = 0.f;
  for (int a = 0; a < 3; ++a) {
    const float extent =
        scene_model == SceneModel::kUnbounded ? 2.f * kContractedExtent : aabb_max[a] - aabb_min[a];
    mean += extent / static_cast<float>(res[a] - 1);
  }
  return mean / 3.f * step_ratio;
}

int SceneField::NumSamples() const {
  if (n_samples > 0) return n_samples;
  const double norm =
      std::sqrt(static_cast<double>(res[0]) * res[0] + static_cast<double>(res[1]) * res[1] +
                static_cast<double>(res[2]) * res[2]);
  const double n = norm / static_cast<double>(step_ratio);
  return n >= 1e9 ? 1000000000 : static_cast<int>(n);
}

Status SceneField::Validate() const {
  ECRF_CHECK_OR_RETURN(
      scene_model == SceneModel::kObject || scene_model == SceneModel::kUnbounded ||
          scene_model == SceneModel::kForward,
      kErrInvalidArgument, "scene: unknown scene model %d", static_cast<int>(scene_model));
  ECRF_CHECK_OR_RETURN(scene_model != SceneModel::kUnbounded || near_far[0] >= 0.f,
                       kErrInvalidArgument, "scene: near is negative in an unbounded scene");
  ECRF_CHECK_OR_RETURN(head == HeadKind::kPerSample || head == HeadKind::kDeferred,
                       kErrInvalidArgument, "scene: unknown head %d", static_cast<int>(head));
  if (scene_model == SceneModel::kForward) {
    bool finite = true;
    for (float v : ndc.world_to_ref) finite = finite && std::isfinite(v);
    ECRF_CHECK_OR_RETURN(
        finite && std::isfinite(ndc.scale[0]) && ndc.scale[0] > 0.f &&
            std::isfinite(ndc.scale[1]) && ndc.scale[1] > 0.f && std::isfinite(ndc.near_plane) &&
            ndc.near_plane > 0.f,
        kErrInvalidArgument,
        "scene: the NDC frame of a forward-facing scene is not finite and positive");
  }
  for (int a = 0; a < 3; ++a) {
    ECRF_CHECK_OR_RETURN(
        std::isfinite(aabb_min[a]) && std::isfinite(aabb_max[a]) && aabb_max[a] > aabb_min[a],
        kErrInvalidArgument, "scene: empty or non-finite aabb on axis %d", a);
    ECRF_CHECK_OR_RETURN(res[a] >= 2 && res[a] <= kMaxGridRes, kErrInvalidArgument,
                         "scene: grid resolution %d on axis %d out of range", res[a], a);
    ECRF_CHECK_OR_RETURN(density.res[a] == res[a] && appearance.res[a] == res[a],
                         kErrInvalidArgument, "scene: grid resolutions differ on axis %d", a);
  }
  ECRF_RETURN_IF_ERROR(density.Validate("density", !grids_known_finite));
  ECRF_RETURN_IF_ERROR(appearance.Validate("appearance", !grids_known_finite));
  ECRF_CHECK_OR_RETURN(std::isfinite(density_shift) && std::isfinite(distance_scale) &&
                           distance_scale >= 0.f && std::isfinite(weight_threshold) &&
                           std::isfinite(near_far[0]) && std::isfinite(near_far[1]) &&
                           near_far[0] <= near_far[1] && std::isfinite(background[0]) &&
                           std::isfinite(background[1]) && std::isfinite(background[2]),
                       kErrInvalidArgument, "scene: non-finite or inconsistent render parameters");
  ECRF_CHECK_OR_RETURN(step_ratio > 0.f && std::isfinite(step_ratio) && std::isfinite(step_size) &&
                           step_size >= 0.f && n_samples >= 0,
                       kErrInvalidArgument, "scene: bad step parameters");
  const float step = StepSize();
  ECRF_CHECK_OR_RETURN(step > 0.f && std::isfinite(step), kErrInvalidArgument,
                       "scene: step size %g is not positive", static_cast<double>(step));
  ECRF_CHECK_OR_RETURN(mlp.initialized(), kErrInvalidArgument, "scene: appearance MLP not set");
  ECRF_CHECK_OR_RETURN(mlp.config().num_products == appearance.total_rank(), kErrInvalidArgument,
                       "scene: MLP expects %d products, appearance grid has %d",
                       mlp.config().num_products, appearance.total_rank());
  if (has_mask) {
    ECRF_CHECK_OR_RETURN(mask.acceleration_ready(), kErrInvalidArgument,
                         "scene: alpha mask acceleration not built (call BuildAcceleration)");
  }
  return Status::Ok();
}

}  // namespace dec
}  // namespace ecrf
