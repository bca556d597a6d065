// The forward-facing scene model (SPEC.md 7.2.2): a world ray is moved into the reference
// camera's frame, started on its near plane and mapped into normalised device coordinates
// (TensoRF's ndc_rays_blender), where it is a straight line again and the object process of 7.2
// samples it.
//
// Header-only and shared by the trainer and the decoder so that both compute every NDC ray with
// the same binary32 operations in the same order (see contraction.h).
#ifndef ECRF_DECODER_NDC_H_
#define ECRF_DECODER_NDC_H_

#include <cmath>

#include "format/ndc_frame.h"

namespace ecrf {

// The NDC origin `ndc_o` (on the near plane, NDC z = -1) and unit direction `ndc_d` of the world
// ray (o, d). False, with the outputs unspecified, for a ray that does not travel towards the
// reference camera's far side (it never reaches NDC z = 1) or whose NDC ray is not finite.
inline bool NdcRay(const NdcFrame& f, const float o[3], const float d[3], float ndc_o[3],
                   float ndc_d[3]) {
  const float* m = f.world_to_ref;
  float ro[3], rd[3];
  for (int a = 0; a < 3; ++a) {
    ro[a] = m[4 * a] * o[0] + m[4 * a + 1] * o[1] + m[4 * a + 2] * o[2] + m[4 * a + 3];
    rd[a] = m[4 * a] * d[0] + m[4 * a + 1] * d[1] + m[4 * a + 2] * d[2];
  }
  if (!(rd[2] < 0.f)) return false;  // also NaN
  const float n = f.near_plane;
  const float s = -(n + ro[2]) / rd[2];
  float on[3];
  for (int a = 0; a < 3; ++a) on[a] = ro[a] + s * rd[a];
  const float x = on[0] / on[2], y = on[1] / on[2];
  ndc_o[0] = -f.scale[0] * x;
  ndc_o[1] = -f.scale[1] * y;
  ndc_o[2] = 1.f + (2.f * n) / on[2];
  float v[3];
  v[0] = -f.scale[0] * (rd[0] / rd[2] - x);
  v[1] = -f.scale[1] * (rd[1] / rd[2] - y);
  v[2] = -(2.f * n) / on[2];
  const float len2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  const float inv = 1.f / std::sqrt(len2);
  for (int a = 0; a < 3; ++a) ndc_d[a] = v[a] * inv;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(ndc_o[a]) || !std::isfinite(ndc_d[a])) return false;
  }
  return len2 > 0.f;
}

}  // namespace ecrf

#endif  // ECRF_DECODER_NDC_H_
