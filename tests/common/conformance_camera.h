// The camera of each scene vector's reference render (SPEC.md 7.7). tests/conformance/manifest.json
// stores the resulting binary32 values exactly; this is how `ecrf conformance --write` made them.
#ifndef ECRF_TESTS_COMMON_CONFORMANCE_CAMERA_H_
#define ECRF_TESTS_COMMON_CONFORMANCE_CAMERA_H_

#include <string>

#include "decoder/camera.h"
#include "decoder/ray_marcher.h"

namespace ecrf {
namespace conformance {

inline constexpr char kBuiltinSceneVector[] = "scene_builtin";

inline dec::Camera ReferenceCamera(const std::string& vector_name) {
  return vector_name == kBuiltinSceneVector ? dec::OrbitCamera(64, 64, 0.3f, 0.45f, 4.0f)
                                            : dec::OrbitCamera(48, 48, 0.7f, 0.5f, 3.5f);
}

}  // namespace conformance
}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_CONFORMANCE_CAMERA_H_
