#include "tools/camera_path_json.h"

#include <stdlib.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "trainer/data/dataset.h"
#include "trainer/data/file_io.h"

namespace ecrf {
namespace tools {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A private directory removed with everything in it when it goes out of scope.
class TemporaryDirectory {
 public:
  TemporaryDirectory() {
    std::error_code error;
    fs::path base = fs::temp_directory_path(error);
    if (error) base = "/tmp";
    std::string pattern = (base / "ecrf_path_XXXXXX").string();
    if (!mkdtemp(pattern.data())) {
      throw std::runtime_error("cannot create a temporary directory in " + base.string() + ": " +
                               std::strerror(errno));
    }
    path_ = pattern;
  }
  ~TemporaryDirectory() {
    std::error_code error;
    fs::remove_all(path_, error);
  }
  TemporaryDirectory(const TemporaryDirectory&) = delete;
  TemporaryDirectory& operator=(const TemporaryDirectory&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

json ReadJsonFile(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file + ": cannot open: " + std::strerror(errno));
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw std::runtime_error(file + ": invalid JSON: " + e.what());
  }
}

// What a dataset needs and a path need not say: the image size (a dataset takes it from the
// images) and each frame's file_path (the image). Anything else is left for the reader to check.
void FillPathDefaults(int width, int height, json* root) {
  if (!root->is_object()) return;
  if (!root->contains("w")) (*root)["w"] = width;
  if (!root->contains("h")) (*root)["h"] = height;
  auto frames = root->find("frames");
  if (frames == root->end() || !frames->is_array()) return;
  for (size_t i = 0; i < frames->size(); ++i) {
    json& frame = (*frames)[i];
    if (!frame.is_object()) continue;
    auto name = frame.find("file_path");
    if (name == frame.end() || !name->is_string() || name->get<std::string>().empty()) {
      frame["file_path"] = FrameName("path", int(i));
    }
  }
}

void ReplaceAll(std::string* text, const std::string& from, const std::string& to) {
  for (size_t at = text->find(from); at != std::string::npos; at = text->find(from, at)) {
    text->replace(at, from.size(), to);
    at += to.size();
  }
}

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
  json root = ReadJsonFile(file);
  FillPathDefaults(default_width, default_height, &root);
  // The reader takes a dataset directory and a split, so the completed file goes into a private
  // directory as its transforms_test.json (the Blender layout: frames in file order, no images
  // needed once w and h are known); its messages then name the user's file again.
  const TemporaryDirectory dir;
  const std::string copy = dir.path() + "/transforms_test.json";
  trainer::WriteFileAtomically(copy, root.dump());
  trainer::DatasetManifest manifest;
  try {
    manifest = trainer::ReadDatasetManifest(dir.path(), "test");
  } catch (const std::runtime_error& e) {
    std::string message = e.what();
    ReplaceAll(&message, copy, file);
    throw std::runtime_error(message);
  }
  std::vector<PathCamera> path;
  for (size_t i = 0; i < manifest.views.size(); ++i) {
    path.push_back({FrameName("path", int(i)), manifest.views[i].camera});
  }
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
