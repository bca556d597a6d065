// The encoder half of the NDCP chunk.
#include "format/ndc_frame.h"

namespace ecrf {

void WriteNdcFrame(const NdcFrame& f, ByteWriter* out) {
  for (float v : f.world_to_ref) out->F32(v);
  out->F32(f.scale[0]);
  out->F32(f.scale[1]);
  out->F32(f.near_plane);
}

}  // namespace ecrf
