// COLMAP's sparse model in its text form (cameras.txt, images.txt) and its conversion into the
// cameras of a transforms.json (the Instant-NGP / nerfstudio layout the trainer reads).
//
// COLMAP stores, per image, the world-to-camera rotation as a unit quaternion (w, x, y, z) and a
// translation, with the camera looking down +z, +y down and +x right (OpenCV). The trainer's
// cameras are camera-to-world in the OpenGL convention (looking down -z, +y up): the camera's
// y and z axes flip. Only the camera models the trainer's loader can express are read: the
// pinhole ones and the radial / OpenCV distortion models (k1, k2, p1, p2).
#ifndef ECRF_TOOLS_PREPARE_COLMAP_MODEL_H_
#define ECRF_TOOLS_PREPARE_COLMAP_MODEL_H_

#include <array>
#include <map>
#include <string>
#include <vector>

#include "trainer/data/named_choice.h"

namespace ecrf {
namespace tools {

// The COLMAP camera models whose distortion the trainer models (`ecrf prepare --camera-model`,
// and what cameras.txt may hold), with their parameter counts in COLMAP's order.
enum class ColmapCameraModel { kOpencv, kRadial, kSimpleRadial, kPinhole, kSimplePinhole };
inline constexpr int kColmapParamCount[] = {
    8,  // fx, fy, cx, cy, k1, k2, p1, p2
    5,  // f, cx, cy, k1, k2
    4,  // f, cx, cy, k
    4,  // fx, fy, cx, cy
    3,  // f, cx, cy
};

}  // namespace tools

template <>
struct trainer::ChoiceNames<tools::ColmapCameraModel> {
  static constexpr const char* what = "camera model";
  static constexpr const char* names[] = {"OPENCV", "RADIAL", "SIMPLE_RADIAL", "PINHOLE",
                                          "SIMPLE_PINHOLE"};
};

namespace tools {

struct ColmapCamera {
  std::string model;  // SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL or OPENCV
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0;
};

struct ColmapImage {
  int camera_id = 0;
  std::string name;  // the image's path relative to COLMAP's image folder
  // Camera-to-world, OpenGL convention (the trainer's Camera::c2w).
  double c2w[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
};

struct ColmapModel {
  std::map<int, ColmapCamera> cameras;  // by COLMAP camera id
  std::vector<ColmapImage> images;      // in images.txt order
};

// Parse the text files; throws std::runtime_error naming the file, the line and what is wrong
// (an unsupported camera model, a malformed line, an image of an unknown camera, a rotation that
// is not a unit quaternion).
std::map<int, ColmapCamera> ParseColmapCameras(const std::string& text, const std::string& where);
std::vector<ColmapImage> ParseColmapImages(const std::string& text, const std::string& where);
// cameras.txt and images.txt of `dir`.
ColmapModel ReadColmapTextModel(const std::string& dir);

// The inverse of ParseColmapImages's pose conversion, for tests and tools that write COLMAP
// models: the quaternion (w, x, y, z) and translation of the world-to-camera transform.
void ColmapPoseFromC2w(const double c2w[3][4], double qvec[4], double tvec[3]);

// A similarity (scale, rotation, translation) that puts the cameras where Instant-NGP's
// colmap2nerf puts them: the mean camera "up" becomes +z, the point the optical axes pass
// closest to (least squares) becomes the origin, and the mean camera distance to it becomes
// `mean_distance`. Applied to every c2w in place; returns the scale factor applied.
double NormalizeColmapPoses(std::vector<ColmapImage>* images, double mean_distance);

// transforms.json text: one shared set of intrinsics when every image has the same camera,
// else per-frame intrinsics; frames sorted by name with file_path "images/NAME"; aabb_scale.
std::string TransformsJson(const ColmapModel& model, const std::vector<ColmapImage>& images,
                           int aabb_scale, const std::string& image_dir);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_PREPARE_COLMAP_MODEL_H_
