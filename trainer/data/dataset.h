// Posed image datasets: NeRF "Blender synthetic", Instant-NGP / nerfstudio transforms.json and
// LLFF poses_bounds.npy.
#ifndef ECRF_TRAINER_DATA_DATASET_H_
#define ECRF_TRAINER_DATA_DATASET_H_

#include <cstdint>
#include <string>
#include <vector>

#include "trainer/data/camera.h"
#include "trainer/data/image_io.h"

namespace ecrf::trainer {

struct View {
  Camera camera;
  Image rgb;  // 3 channels, alpha composited on white
  std::string name;
  // A held-out view whose camera was fitted to its image (AlignHeldOutCameras): columns
  // [0, fitted_columns) fitted it and are never scored; scores cover the columns right of them
  // (the half-image protocol). 0: nothing of the view was fitted, the whole view is scored.
  int fitted_columns = 0;
  // The half-image protocol for appearance (a capture trained with per-image exposure codes, which
  // the file leaves out): the view's per-channel gain is fitted on columns [0, fitted_columns)
  // and applied to the render before the rest is scored (WithExposureFit).
  bool fit_exposure = false;
};

struct Dataset {
  std::vector<View> views;
  double scene_aabb[2][3] = {{-1.5, -1.5, -1.5}, {1.5, 1.5, 1.5}};  // min corner, max corner
  double near = 2.0;
  double far = 6.0;
  bool white_background = true;  // background pixels are white (transparent pixels composited)
  // The poses were estimated (structure from motion: the Instant-NGP / nerfstudio and LLFF
  // layouts) and are a few pixels off, unlike the rendered cameras of the Blender layout and of
  // the procedural scenes: what --refine-cameras auto goes by.
  bool estimated_poses = false;
  // The cameras were refined already, by a camera warm-up (trainer/train/camera_warmup.h): the
  // run refines them from later on (kRefineCamerasFromWarmedUp).
  bool warmed_up_cameras = false;
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
  bool estimated_poses = false;  // as Dataset::estimated_poses
  int prescaled = 1;  // the images are already this factor smaller (LLFF images_N folders)
};

// Reads the cameras of `split` ("train", "val" or "test") from `dir`:
//  * dir/transforms_{split}.json (NeRF Blender layout, also accepted with Instant-NGP fields):
//    aabb [-1.5, 1.5]^3, near 2, far 6, white background — the conventions published numbers use.
//  * otherwise dir/transforms.json (Instant-NGP / nerfstudio): frames are sorted by file_path
//    and every 8th (index % 8 == 0) is held out as "test" (and "val"), the rest is "train",
//    the LLFF convention. Frames whose image is missing are skipped with a warning on stderr.
//  * otherwise dir/poses_bounds.npy with dir/images (LLFF; see trainer/data/llff.h), which picks
//    dir/images_<k> for the largest factor k of downscale that is there, and sets `prescaled`.
// Throws std::runtime_error naming the file and the problem for anything malformed.
DatasetManifest ReadDatasetManifest(const std::string& dir, const std::string& split,
                                    int downscale = 1);

// The cameras of one transforms file (the Blender layout of transforms_SPLIT.json, or a camera
// path), in file order and without images: `file_path` is not needed, and a size the file does not
// give (w and h, top level or per frame) is default_width x default_height. The same fields and
// checks as ReadDatasetManifest; throws std::runtime_error naming the file, the frame and the
// problem.
std::vector<Camera> ReadTransformsCameras(const std::string& json_path, int default_width,
                                          int default_height);

// The pixels a dataset may hold once loaded and downscaled, over all its views: 2^30 (12 GiB as
// float RGB), checked from the cameras' sizes before any image is read.
inline constexpr int64_t kMaxDatasetPixels = int64_t{1} << 30;

// The pixels `views` hold once their images are shrunk by `image_downscale` (each side rounded
// down, as DownscaleArea does): what LoadViews checks against kMaxDatasetPixels.
int64_t LoadedPixels(const std::vector<ViewSource>& views, int image_downscale);

// How much LoadDataset shrinks the images of `manifest` for a run's `downscale`: what the
// folder's own copies (LLFF images_N, `prescaled`) have not done already.
inline int ImageDownscale(const DatasetManifest& manifest, int downscale) {
  return downscale / manifest.prescaled;
}

// Decodes the images in parallel (OpenMP), composites them on white and downscales them with
// DownscaleArea; the cameras are scaled to match. Throws the first failing view's error
// (by view order, so the message does not depend on thread timing).
std::vector<View> LoadViews(const std::vector<ViewSource>& sources, int downscale);

// Instant-NGP maps the NeRF world into its unit cube as p * scale + offset, defaulting to
// scale 0.33 and offset 0.5, and its render box is the unit cube grown about (0.5, 0.5, 0.5)
// by aabb_scale. Mapped back, the box is centred at (0.5 - offset) / scale with half extent
// 0.5 * aabb_scale / scale: about [-1.5, 1.5]^3 * aabb_scale, the Blender box for aabb_scale 1.
inline constexpr double kNgpDefaultScale = 0.33;
inline constexpr double kNgpDefaultOffset[3] = {0.5, 0.5, 0.5};
void NgpAabb(double aabb_scale, double scale, const double offset[3], double aabb[2][3]);

// Real captures have no agreed near/far, so derive them from the geometry: near is the
// smallest camera-to-box distance (the box holds everything modelled; at least 1% of its
// diagonal, to keep samples off the lens of a camera inside it), far the largest distance from
// a camera to a box corner (no ray leaves the box later).
void NearFarFromCameras(const std::vector<Camera>& cameras, const double aabb[2][3], double* near,
                        double* far);

// The views area-filtered to 1/factor of their size with their cameras scaled to match (what
// --downscale does at load time), for evaluating at less than capture resolution.
Dataset DownscaleViews(Dataset dataset, int factor);

// ReadDatasetManifest + LoadViews. downscale >= 1.
Dataset LoadDataset(const std::string& dir, const std::string& split, int downscale);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_DATA_DATASET_H_
