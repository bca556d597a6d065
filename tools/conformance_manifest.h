// tests/conformance/manifest.json (SPEC.md 6.5, 7.1, 7.7): every vector's shape, coding parameters
// and checksums, and the exact binary32 camera of each scene's reference render, as hexadecimal
// floating-point strings so that no parser rounds them.
#ifndef ECRF_TOOLS_CONFORMANCE_MANIFEST_H_
#define ECRF_TOOLS_CONFORMANCE_MANIFEST_H_

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"

namespace ecrf {
namespace tools {

// "%a" of a binary32 value, e.g. "0x1.8p+5"; exact.
std::string HexFloat(float v);
// Parses a hexadecimal (or decimal) floating-point string; throws naming `what` unless the value
// is exactly representable as binary32 and finite.
float ParseExactFloat(const std::string& text, const std::string& what);

nlohmann::json CameraJson(const dec::Camera& camera);
dec::Camera CameraFromJson(const nlohmann::json& j, const std::string& what);

struct SceneChecksums {
  std::string grids, occupancy, mlp;
};
SceneChecksums ComputeSceneChecksums(const dec::SceneField& field);

// The manifest entry of one scene vector: what the stream holds (from the decoder) and its
// checksums and reference camera.
nlohmann::json SceneVectorJson(const std::string& file, size_t bytes, const dec::SceneField& field,
                               const dec::SceneInfo& info, const SceneChecksums& checksums,
                               const dec::Camera& camera, const std::string& png);

// The manifest as text: objects one member per line, arrays of numbers and strings on one line.
std::string ManifestText(const nlohmann::json& manifest);

// How far a render is from a reference render (SPEC.md 7.7): pixels whose largest channel
// difference is at most 2 code values, and the PSNR of the 8-bit values.
struct RenderAgreement {
  size_t pixels = 0;
  size_t within_two_codes = 0;
  int max_difference = 0;
  double psnr_db = 0.0;
  bool Conforms() const { return within_two_codes * 100 >= pixels * 99; }
};
// rgba8: width*height*4 bytes of the render; reference: width*height*3 bytes.
RenderAgreement CompareRenders(const std::vector<uint8_t>& rgba8,
                               const std::vector<uint8_t>& reference_rgb8);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_CONFORMANCE_MANIFEST_H_
