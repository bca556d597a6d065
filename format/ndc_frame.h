// The NDCP chunk: the projective frame of a forward-facing scene (SPEC.md 6.2.1, 7.2.2).
// A forward-facing capture sees its scene through one window; the normalised device coordinates
// (NDC) of a reference camera map the depths from its near plane to infinity onto [-1, 1], so
// one grid covers everything the views see, near things finely and the far wall coarsely.
#ifndef ECRF_FORMAT_NDC_FRAME_H_
#define ECRF_FORMAT_NDC_FRAME_H_

#include <cstddef>
#include <cstdint>

#include "format/byte_io.h"
#include "format/container.h"
#include "format/status.h"

namespace ecrf {

constexpr uint32_t kChunkNdcFrame = FourCC("NDCP");
constexpr size_t kNdcFrameBytes = 60;

struct NdcFrame {
  // World to reference-camera coordinates, row-major 3x4 [A | b]: p_ref = A p + b. The
  // reference camera looks along -z (OpenGL). A may scale: it also sets the scene's unit.
  float world_to_ref[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  // 2 fx / width and 2 fy / height of the reference camera: NDC x and y are -scale * x / z.
  float scale[2] = {1.f, 1.f};
  // Distance of the near plane in front of the reference camera (reference units): NDC z = -1.
  float near_plane = 1.f;
};

void WriteNdcFrame(const NdcFrame& frame, ByteWriter* out);
// Parses and validates an NDCP payload (exactly kNdcFrameBytes): every value finite, both
// scales and the near plane positive.
Status ParseNdcFrame(const uint8_t* payload, size_t size, NdcFrame* frame);

}  // namespace ecrf

#endif  // ECRF_FORMAT_NDC_FRAME_H_
