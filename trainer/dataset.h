// Posed image datasets: NeRF "Blender synthetic" and Instant-NGP / nerfstudio transforms.json.
#ifndef ECRF_TRAINER_DATASET_H_
#define ECRF_TRAINER_DATASET_H_

#include <string>
#include <vector>

#include "trainer/camera.h"
#include "trainer/image_io.h"

namespace ecrf::trainer {

struct View {
  Camera camera;
  Image rgb;  // 3 channels, alpha composited on white
  std::string name;
};

struct Dataset {
  std::vector<View> views;
  double scene_aabb[2][3] = {{-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5}};  // min corner, max corner
  double near = 2.0;
  double far = 6.0;
  bool white_background = true;  // background pixels are white (transparent pixels composited)
};

// A view before its image is decoded: what the JSON says.
struct ViewSource {
  Camera camera;           // full resolution, size taken from the JSON or the image header
  std::string image_path;  // resolved path of the image file
  std::string name;        // file_path from the JSON without "./" and extension
};

// Everything about a split except the pixels; cheap to read (image headers at most).
struct DatasetManifest {
  std::vector<ViewSource> views;
  double scene_aabb[2][3] = {{-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5}};
  double near = 2.0;
  double far = 6.0;
  bool white_background = true;
};

// Reads the cameras of `split` ("train", "val" or "test") from `dir`:
//  * dir/transforms_{split}.json (NeRF Blender layout, also accepted with Instant-NGP fields):
//    aabb [-1.5, 1.5]^3, near 2, far 6, white background — the conventions published numbers use.
//  * otherwise dir/transforms.json (Instant-NGP / nerfstudio): frames are sorted by file_path
//    and every 8th (index % 8 == 0) is held out as "test" (and "val"), the rest is "train",
//    the LLFF convention. Frames whose image is missing are skipped with a warning on stderr.
// Throws std::runtime_error naming the file and the problem for anything malformed.
DatasetManifest ReadDatasetManifest(const std::string& dir, const std::string& split);

// Decodes the images in parallel (OpenMP), composites them on white and downscales them with
// DownscaleArea; the cameras are scaled to match. Throws the first failing view's error
// (by view order, so the message does not depend on thread timing).
std::vector<View> LoadViews(const std::vector<ViewSource>& sources, int downscale);

// ReadDatasetManifest + LoadViews. downscale >= 1.
Dataset LoadDataset(const std::string& dir, const std::string& split, int downscale);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_DATASET_H_
