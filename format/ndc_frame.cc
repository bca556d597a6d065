#include "format/ndc_frame.h"

#include <cmath>

namespace ecrf {

Status ParseNdcFrame(const uint8_t* payload, size_t size, NdcFrame* f) {
  ECRF_CHECK_OR_RETURN(size == kNdcFrameBytes, kErrCorrupt,
                       "NDCP: payload is %zu bytes, must be %zu", size, kNdcFrameBytes);
  ByteReader r(payload, size);
  for (float& v : f->world_to_ref) {
    ECRF_RETURN_IF_ERROR(r.ReadF32(&v, "NDCP world_to_ref"));
    ECRF_CHECK_OR_RETURN(std::isfinite(v), kErrCorrupt, "NDCP: world_to_ref is not finite");
  }
  const char* names[3] = {"scale_x", "scale_y", "near_plane"};
  float* values[3] = {&f->scale[0], &f->scale[1], &f->near_plane};
  for (int k = 0; k < 3; ++k) {
    ECRF_RETURN_IF_ERROR(r.ReadF32(values[k], names[k]));
    ECRF_CHECK_OR_RETURN(std::isfinite(*values[k]) && *values[k] > 0.f, kErrCorrupt,
                         "NDCP: %s must be positive and finite", names[k]);
  }
  return Status::Ok();
}

}  // namespace ecrf
