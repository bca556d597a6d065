// The encoder half of the HEAD chunk (SPEC.md 4.1).
#include "format/scene_header.h"

namespace ecrf {

void WriteSceneHeader(const SceneHeader& h, int version_minor, ByteWriter* out) {
  for (float v : h.aabb_min) out->F32(v);
  for (float v : h.aabb_max) out->F32(v);
  for (uint16_t v : h.res) out->U16(v);
  for (int g = 0; g < kNumSceneGrids; ++g) {
    for (uint16_t v : h.ranks[g]) out->U16(v);
  }
  out->F32(h.density_shift);
  out->F32(h.distance_scale);
  out->F32(h.step_size);
  out->U32(h.num_samples);
  out->F32(h.weight_threshold);
  out->F32(h.near_far[0]);
  out->F32(h.near_far[1]);
  for (float v : h.background) out->F32(v);
  out->U16(h.feature_dim);
  out->U8(h.feature_pe_freqs);
  out->U8(h.viewdir_pe_freqs);
  out->U16(h.hidden);
  out->U8(h.has_occupancy);
  out->U8(h.scene_model);
  if (version_minor >= kDensityActivationMinVersionMinor) out->U8(h.density_activation);
}

}  // namespace ecrf
