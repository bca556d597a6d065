// The camera of each scene vector's reference render (SPEC.md 7.7). tests/conformance/manifest.json
// stores the resulting binary32 values exactly; this is how `ecrf conformance --write` made them.
#ifndef ECRF_CONFORMANCE_CONFORMANCE_CAMERA_H_
#define ECRF_CONFORMANCE_CONFORMANCE_CAMERA_H_

#include <string>

#include "decoder/camera.h"
#include "decoder/ray_marcher.h"

namespace ecrf {
namespace conformance {

inline constexpr char kBuiltinSceneVector[] = "scene_builtin";

// scene_forward_side_view is seen from 95 degrees around from its reference camera: a quarter
// of its rays point away from the reference camera's far side (SPEC.md 7.2.2: background).
inline dec::Camera ReferenceCamera(const std::string& vector_name) {
  if (vector_name == kBuiltinSceneVector) return dec::OrbitCamera(64, 64, 0.3f, 0.45f, 4.0f);
  if (vector_name == "scene_forward_side_view") {
    return dec::OrbitCamera(48, 48, 0.7f + 1.6580628f, 0.5f, 3.5f);
  }
  return dec::OrbitCamera(48, 48, 0.7f, 0.5f, 3.5f);
}

}  // namespace conformance
}  // namespace ecrf

#endif  // ECRF_CONFORMANCE_CONFORMANCE_CAMERA_H_
