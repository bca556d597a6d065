#include "tools/conformance_manifest.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "conformance/grid_md5.h"

namespace ecrf {
namespace tools {

using nlohmann::json;

std::string HexFloat(float v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%a", static_cast<double>(v));
  return buf;
}

float ParseExactFloat(const std::string& text, const std::string& what) {
  errno = 0;
  char* end = nullptr;
  const double d = std::strtod(text.c_str(), &end);
  const float f = static_cast<float>(d);
  if (text.empty() || end != text.c_str() + text.size() || errno != 0 || !std::isfinite(d) ||
      static_cast<double>(f) != d) {
    throw std::runtime_error(what + ": \"" + text +
                             "\" is not a finite binary32 value written exactly");
  }
  return f;
}

json CameraJson(const dec::Camera& camera) {
  json c2w = json::array();
  for (float v : camera.c2w) c2w.push_back(HexFloat(v));
  return json{{"width", camera.width},
              {"height", camera.height},
              {"fx", HexFloat(camera.fx)},
              {"fy", HexFloat(camera.fy)},
              {"cx", HexFloat(camera.cx)},
              {"cy", HexFloat(camera.cy)},
              {"c2w", c2w}};
}

dec::Camera CameraFromJson(const json& j, const std::string& what) {
  dec::Camera cam;
  if (!j.is_object() || !j.contains("c2w") || !j["c2w"].is_array() || j["c2w"].size() != 12) {
    throw std::runtime_error(what +
                             ": a camera needs width, height, fx, fy, cx, cy and 12 c2w entries");
  }
  cam.width = j.at("width").get<int>();
  cam.height = j.at("height").get<int>();
  cam.fx = ParseExactFloat(j.at("fx").get<std::string>(), what + ".fx");
  cam.fy = ParseExactFloat(j.at("fy").get<std::string>(), what + ".fy");
  cam.cx = ParseExactFloat(j.at("cx").get<std::string>(), what + ".cx");
  cam.cy = ParseExactFloat(j.at("cy").get<std::string>(), what + ".cy");
  for (int i = 0; i < 12; ++i) {
    cam.c2w[i] =
        ParseExactFloat(j["c2w"][i].get<std::string>(), what + ".c2w[" + std::to_string(i) + "]");
  }
  if (cam.width < 1 || cam.height < 1 || cam.width > 4096 || cam.height > 4096) {
    throw std::runtime_error(what + ": image size out of range");
  }
  return cam;
}

SceneChecksums ComputeSceneChecksums(const dec::SceneField& field) {
  return {conformance::SceneGridMd5(field), conformance::OccupancyMd5(field),
          conformance::MlpMd5(field)};
}

namespace {

json Triple(const uint16_t v[3]) { return json::array({v[0], v[1], v[2]}); }

// The block shape of the first coded plane and line tensor (the vectors use one of each).
json BlockShapes(const dec::SceneInfo& info) {
  json shapes = json::object();
  for (int g = 0; g < kNumSceneGrids; ++g) {
    for (int t = 0; t < kTensorsPerSceneGrid; ++t) {
      const dec::TensorChunkInfo& ti = info.tensors[g][t];
      const char* kind = t < 3 ? "plane" : "line";
      if (ti.present && !shapes.contains(kind))
        shapes[kind] = {ti.block[0], ti.block[1], ti.block[2]};
    }
  }
  return shapes;
}

int CoefBits(const dec::SceneInfo& info) {
  for (const auto& grid : info.tensors) {
    for (const auto& ti : grid) {
      if (ti.present) return ti.coef_bits;
    }
  }
  return 0;
}

}  // namespace

json SceneVectorJson(const std::string& file, size_t bytes, const dec::SceneField& field,
                     const dec::SceneInfo& info, const SceneChecksums& checksums,
                     const dec::Camera& camera, const std::string& png) {
  const char* mlp = info.mlp_precision == 2   ? "quantized"
                    : info.mlp_precision == 1 ? "float32"
                                              : "float16";
  json occupancy = nullptr;
  if (field.has_mask) occupancy = {field.mask.res()[0], field.mask.res()[1], field.mask.res()[2]};
  json entry{
      {"file", file},
      {"bytes", bytes},
      {"version", std::to_string(info.version_major) + "." + std::to_string(info.version_minor)},
      {"grid", Triple(info.header.res)},
      {"ranks",
       {{"density", Triple(info.header.ranks[0])}, {"appearance", Triple(info.header.ranks[1])}}},
      {"blocks", BlockShapes(info)},
      {"coef_bits", CoefBits(info)},
      {"mlp", mlp},
      {"occupancy", occupancy},
      {"md5",
       {{"grids", checksums.grids}, {"occupancy", checksums.occupancy}, {"mlp", checksums.mlp}}},
      {"render", {{"png", png}, {"camera", CameraJson(camera)}}}};
  // Object scenes (every vector before bitstream 1.2) leave the key out.
  if (field.scene_model != SceneModel::kObject)
    entry["scene_model"] = SceneModelName(field.scene_model);
  return entry;
}

namespace {

void AppendPretty(const json& j, int indent, std::string* out) {
  const bool flat = !j.is_structured() ||
                    (j.is_array() && std::none_of(j.begin(), j.end(),
                                                  [](const json& e) { return e.is_structured(); }));
  if (flat) {
    *out += j.dump();
    return;
  }
  const std::string pad(size_t(indent + 1) * 2, ' ');
  *out += j.is_array() ? "[\n" : "{\n";
  size_t i = 0;
  for (auto it = j.begin(); it != j.end(); ++it, ++i) {
    *out += pad;
    if (j.is_object()) *out += json(it.key()).dump() + ": ";
    AppendPretty(*it, indent + 1, out);
    *out += i + 1 < j.size() ? ",\n" : "\n";
  }
  *out += std::string(size_t(indent) * 2, ' ') + (j.is_array() ? "]" : "}");
}

}  // namespace

std::string ManifestText(const json& manifest) {
  std::string out;
  AppendPretty(manifest, 0, &out);
  return out + "\n";
}

RenderAgreement CompareRenders(const std::vector<uint8_t>& rgba8,
                               const std::vector<uint8_t>& reference_rgb8) {
  RenderAgreement a;
  a.pixels = reference_rgb8.size() / 3;
  if (rgba8.size() != a.pixels * 4) throw std::runtime_error("CompareRenders: image sizes differ");
  double sse = 0.0;
  for (size_t p = 0; p < a.pixels; ++p) {
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int d = std::abs(int(rgba8[p * 4 + c]) - int(reference_rgb8[p * 3 + c]));
      worst = std::max(worst, d);
      sse += double(d) * d / (255.0 * 255.0);
    }
    a.within_two_codes += worst <= 2;
    a.max_difference = std::max(a.max_difference, worst);
  }
  const double mse = a.pixels ? sse / double(a.pixels * 3) : 0.0;
  a.psnr_db = mse > 0 ? -10.0 * std::log10(mse) : 99.0;
  return a;
}

}  // namespace tools
}  // namespace ecrf
