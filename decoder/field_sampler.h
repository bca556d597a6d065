// Point queries on a SceneField's VM grids: grid location (align_corners=True, clamped), density
// feature (sum over modes and ranks of bilinear plane * linear line) and appearance products.
// Both storages (float32 and int16 * per-tensor scale) go through one template.
#ifndef ECRF_DECODER_FIELD_SAMPLER_H_
#define ECRF_DECODER_FIELD_SAMPLER_H_

#include <cstdint>

#include "decoder/density_activation.h"
#include "decoder/field.h"
#include "decoder/grid_point.h"

namespace ecrf {
namespace dec {

// Density feature (no shift): sum_m sum_r plane_m[r](u,v) * line_m[r](w).
float DensityFeature(const VmGrid& grid, const GridPoint& gp);
// out[rank_offset(m) + r] = plane_m[r](u,v) * line_m[r](w), total_rank() floats.
void AppearanceProducts(const VmGrid& grid, const GridPoint& gp, float* out);
// sum[k] += weight * products[k] for the products above, without storing them.
void AccumulateAppearanceProducts(const VmGrid& grid, const GridPoint& gp, float weight,
                                  float* sum);

// dst = src (float32) as int16 fixed point, one scale per tensor (max |value| / 32767, 1 for an
// all-zero tensor), q = round(value / scale).
Status QuantizeGridInt16(const VmGrid& src, VmGrid* dst);

}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_DECODER_FIELD_SAMPLER_H_
