// ecrf_export_capture DIR [--size WxH] [--frames N] [--seed S]: the procedural phone capture
// (`ecrf train --scene capture`) as files, for measuring `ecrf prepare` against the truth:
//   DIR/photos/frame_NNN.png           the frames, for `ecrf prepare DIR/photos -o DATA`
//   DIR/truth/transforms.json, images/ the same frames with their true cameras (Instant-NGP layout)
// Then `ecrf train --data DIR/truth` and `ecrf train --data DATA` train on the true and on the
// recovered cameras alike (docs/photos-to-dataset.md).
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "trainer/data/image_io.h"
#include "trainer/scenes/capture_scene.h"

namespace fs = std::filesystem;
using namespace ecrf;

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::fprintf(stderr, "usage: ecrf_export_capture DIR [--size WxH] [--frames N] [--seed S]\n");
    return 2;
  }
  const std::string dir = argv[1];
  int width = 320, height = 240, frames = 48;
  unsigned seed = 7;  // the seed of PrepareDatasetTest.PosesEveryPhotoOfARenderedCapture
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i], value = argv[i + 1];
    if (flag == "--size" && std::sscanf(value.c_str(), "%dx%d", &width, &height) == 2) continue;
    if (flag == "--frames") {
      frames = std::atoi(value.c_str());
      continue;
    }
    if (flag == "--seed") {
      seed = unsigned(std::strtoul(value.c_str(), nullptr, 10));
      continue;
    }
    std::fprintf(stderr, "ecrf_export_capture: bad option '%s %s'\n", flag.c_str(), value.c_str());
    return 2;
  }
  try {
    if (fs::exists(dir) && !fs::is_empty(dir)) {
      std::fprintf(stderr, "ecrf_export_capture: %s exists and is not empty\n", dir.c_str());
      return 1;
    }
    fs::create_directories(dir + "/photos");
    fs::create_directories(dir + "/truth/images");
    nlohmann::json frames_json = nlohmann::json::array();
    trainer::Camera first;
    for (const char* split : {"train", "test"}) {
      const trainer::Dataset capture =
          trainer::MakeCaptureScene(split, width, height, frames, seed);
      for (const trainer::View& v : capture.views) {
        const std::string name = v.name.substr(v.name.find('/') + 1) + ".png";  // frame_NNN.png
        trainer::SavePng(dir + "/photos/" + name, v.rgb);
        trainer::SavePng(dir + "/truth/images/" + name, v.rgb);
        nlohmann::json m = nlohmann::json::array();
        for (int r = 0; r < 4; ++r) {
          m.push_back(r < 3 ? nlohmann::json{v.camera.c2w[r][0], v.camera.c2w[r][1],
                                             v.camera.c2w[r][2], v.camera.c2w[r][3]}
                            : nlohmann::json{0.0, 0.0, 0.0, 1.0});
        }
        frames_json.push_back({{"file_path", "images/" + name}, {"transform_matrix", m}});
        first = v.camera;
      }
    }
    // One phone: every frame has the same intrinsics.
    const nlohmann::json truth = {{"w", width},
                                  {"h", height},
                                  {"fl_x", first.fx},
                                  {"fl_y", first.fy},
                                  {"cx", first.cx},
                                  {"cy", first.cy},
                                  {"k1", first.k1},
                                  {"k2", first.k2},
                                  {"p1", first.p1},
                                  {"p2", first.p2},
                                  {"aabb_scale", int(trainer::kCaptureAabbScale)},
                                  {"frames", frames_json}};
    std::ofstream(dir + "/truth/transforms.json") << truth.dump(2) << "\n";
    std::printf("%s/photos: %d frames of %dx%d; true cameras in %s/truth/transforms.json\n",
                dir.c_str(), frames, width, height, dir.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ecrf_export_capture: %s\n", e.what());
    return 1;
  }
  return 0;
}
