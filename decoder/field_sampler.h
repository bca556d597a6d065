// Point queries on a SceneField's VM grids: grid location (align_corners=True, clamped), density
// feature (sum over modes and ranks of bilinear plane * linear line) and appearance products.
// Both storages (float32 and int16 * per-tensor scale) go through one template.
#ifndef ECRF_DECODER_FIELD_SAMPLER_H_
#define ECRF_DECODER_FIELD_SAMPLER_H_

#include <cstdint>

#include "decoder/field.h"

namespace ecrf {
namespace dec {

// Lower corner index and upper-corner weight per axis of one sample (shared by both grids).
struct GridPoint {
  int i0[3];
  float f[3];
};

// c: normalized coordinates in [-1,1]^3 (c = (x - min) * 2/(max - min) - 1). Continuous index
// (c+1)/2*(res-1) clamped to [0, res-1] (NaN -> 0); i0 in [0, res-2], f in [0,1].
inline void LocateGridPoint(const float c[3], const int res[3], GridPoint* gp) {
  for (int a = 0; a < 3; ++a) {
    const int n = res[a];
    float idx = (c[a] + 1.f) / 2.f * static_cast<float>(n - 1);
    if (!(idx > 0.f)) idx = 0.f;
    if (idx > static_cast<float>(n - 1)) idx = static_cast<float>(n - 1);
    int i = static_cast<int>(idx);
    if (i > n - 2) i = n - 2;
    gp->i0[a] = i;
    gp->f[a] = idx - static_cast<float>(i);
  }
}

// Density feature (no shift): sum_m sum_r plane_m[r](u,v) * line_m[r](w).
float DensityFeature(const VmGrid& grid, const GridPoint& gp);
// out[rank_offset(m) + r] = plane_m[r](u,v) * line_m[r](w), total_rank() floats.
void AppearanceProducts(const VmGrid& grid, const GridPoint& gp, float* out);

// dst = src (float32) as int16 fixed point, one scale per tensor (max |value| / 32767, 1 for an
// all-zero tensor), q = round(value / scale).
Status QuantizeGridInt16(const VmGrid& src, VmGrid* dst);

// PyTorch softplus (threshold 20).
float Softplus(float x);

}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_DECODER_FIELD_SAMPLER_H_
