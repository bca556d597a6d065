// Camera paths as JSON files (`ecrf render --path FILE`, `--save-path FILE`), in the
// transforms.json convention the datasets use: a top-level object with the intrinsics
// (camera_angle_x, or fl_x / fl_y / cx / cy, and w / h) and `frames`, each with a 4x4
// camera-to-world `transform_matrix` (OpenGL axes: the camera looks down -z, +y up). A path needs
// no images, so `file_path` may be left out, and w / h default to the command's -W / -H.
#ifndef ECRF_TOOLS_CAMERA_PATH_JSON_H_
#define ECRF_TOOLS_CAMERA_PATH_JSON_H_

#include <string>
#include <vector>

#include "tools/camera_path.h"

namespace ecrf {
namespace tools {

// The cameras of `file`, in file order, named path_000, path_001, ... Read by the datasets' own
// transforms reader (trainer::ReadTransformsCameras), so a path accepts and checks exactly what a
// Blender transforms_SPLIT.json does, distortion and per-frame intrinsics included. Throws
// std::runtime_error naming the file, the frame and the problem.
std::vector<PathCamera> ReadCameraPath(const std::string& file, int default_width,
                                       int default_height);

// The path as JSON text that ReadCameraPath reads back to the same cameras, bit for bit: shared
// intrinsics at the top level when every camera has the same, else in each frame; file_path is
// the camera's name.
std::string CameraPathJson(const std::vector<PathCamera>& path);

// CameraPathJson written atomically (a temporary file renamed into place).
void WriteCameraPath(const std::string& file, const std::vector<PathCamera>& path);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_CAMERA_PATH_JSON_H_
