// LLFF captures (the NeRF "real forward-facing" layout): poses_bounds.npy plus images/.
#ifndef ECRF_TRAINER_DATA_LLFF_H_
#define ECRF_TRAINER_DATA_LLFF_H_

#include <string>

#include "trainer/data/dataset.h"

namespace ecrf::trainer {

// Reads dir/poses_bounds.npy (N x 17: a row-major 3x5 [R | t | (h, w, focal)] in LLFF's
// [down, right, back] camera axes, then the near and far depth bounds) and the N images of
// dir/images sorted by name. With downscale > 1 it uses dir/images_<downscale> when that
// exists, as LLFF does, and sets *prescaled to downscale (LoadViews must not shrink again);
// otherwise *prescaled is 1 and the images are full size.
// Conventions follow NeRF's load_llff_data: axes turned to OpenGL [right, up, back]; the scene
// scaled so the nearest bound is 1 / 0.75; poses recentred on their average pose; every 8th
// image (0, 8, ...) is "test" and "val", the rest "train"; focal length scaled to the image
// size, principal point at the centre; near 0.9 x the smallest bound and far the largest
// (after scaling). The aabb is the box around the camera centres and the four corner rays of
// every camera between its near and far bounds; the forward-facing scene model (scene_fit.h)
// replaces it with an NDC box whose near plane, 0.75 / 0.9 of `near`, is 1 as in TensoRF.
// Throws std::runtime_error naming the file and the problem: a malformed .npy, a shape other
// than N x 17, non-finite or non-positive values, a pose count that does not match the images.
DatasetManifest ReadLlffManifest(const std::string& dir, const std::string& split, int downscale,
                                 int* prescaled);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_DATA_LLFF_H_
