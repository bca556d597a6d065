#include "tools/camera_path_json.h"

#include <nlohmann/json.hpp>
#include <stdexcept>

#include "trainer/data/dataset.h"
#include "trainer/data/file_io.h"

namespace ecrf {
namespace tools {
namespace {

using nlohmann::json;

json IntrinsicsJson(const trainer::Camera& c) {
  json j = {{"w", c.width}, {"h", c.height}, {"fl_x", c.fx},
            {"fl_y", c.fy}, {"cx", c.cx},    {"cy", c.cy}};
  if (c.HasDistortion()) {
    j["k1"] = c.k1;
    j["k2"] = c.k2;
    j["p1"] = c.p1;
    j["p2"] = c.p2;
  }
  return j;
}

json MatrixJson(const double c2w[3][4]) {
  json m = json::array();
  for (int r = 0; r < 3; ++r) m.push_back({c2w[r][0], c2w[r][1], c2w[r][2], c2w[r][3]});
  m.push_back({0.0, 0.0, 0.0, 1.0});
  return m;
}

}  // namespace

std::vector<PathCamera> ReadCameraPath(const std::string& file, int default_width,
                                       int default_height) {
  const std::vector<trainer::Camera> cameras =
      trainer::ReadTransformsCameras(file, default_width, default_height);
  std::vector<PathCamera> path;
  for (size_t i = 0; i < cameras.size(); ++i)
    path.push_back({FrameName("path", int(i)), cameras[i]});
  return path;
}

std::string CameraPathJson(const std::vector<PathCamera>& path) {
  bool shared = !path.empty();
  for (const PathCamera& p : path)
    shared = shared && IntrinsicsJson(p.camera) == IntrinsicsJson(path[0].camera);
  json root = shared ? IntrinsicsJson(path[0].camera) : json::object();
  json frames = json::array();
  for (const PathCamera& p : path) {
    json frame = shared ? json::object() : IntrinsicsJson(p.camera);
    frame["file_path"] = p.name;
    frame["transform_matrix"] = MatrixJson(p.camera.c2w);
    frames.push_back(std::move(frame));
  }
  root["frames"] = std::move(frames);
  return root.dump(2) + "\n";
}

void WriteCameraPath(const std::string& file, const std::vector<PathCamera>& path) {
  trainer::WriteFileAtomically(file, CameraPathJson(path));
}

}  // namespace tools
}  // namespace ecrf
