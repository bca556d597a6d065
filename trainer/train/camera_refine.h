// Photometric camera refinement: the poses (and the shared intrinsics) that structure from motion
// gives are a few pixels off, and a radiance field trained on them blurs what it cannot place
// (the procedural capture posed by COLMAP trained 4.6 dB below the same images on their true
// cameras; docs/photos-to-dataset.md). This refines each camera against the field being trained, as
// bundle adjustment refines them against points, and as nerfstudio's camera optimizer does by
// gradient descent.
//
// How: Levenberg-Marquardt on the pixels' colour residuals gain_v * render(camera_v, pixel) -
// image_v(pixel), over a subset of pixels per view (the most textured of a random draw: flat
// pixels say nothing about where a camera is). The Jacobian comes from central differences of the
// renderer (RenderRays: deterministic, no jitter), each parameter stepped by about half a pixel of
// image motion. Unknowns: per view a rotation about the camera centre and a translation, both in
// the camera's own frame; with `intrinsics`, and when every view has the same intrinsics, the
// shared focal length (fx and fy at their ratio), principal point, k1, p1 and p2 too (solved
// jointly through the Schur complement of the per-view blocks). A step is kept only if it lowers
// the subset's mean squared error.
#ifndef ECRF_TRAINER_TRAIN_CAMERA_REFINE_H_
#define ECRF_TRAINER_TRAIN_CAMERA_REFINE_H_

#include <cstdint>
#include <vector>

#include "trainer/data/dataset.h"
#include "trainer/model/tensorf_model.h"

namespace ecrf {
namespace trainer {

struct CameraRefineOptions {
  int pixels_per_view = 512;  // residual pixels per view (of 4x as many random ones)
  bool left_half = false;     // pixels only from the left half of each view (columns < width / 2)
  int steps = 3;              // Levenberg-Marquardt steps
  bool intrinsics = true;     // also the shared intrinsics (only when all views share them)
  uint64_t seed = 1;          // which pixels
};

struct CameraRefineStats {
  double mse_before = 0.0, mse_after = 0.0;  // over the chosen pixels
  int steps_taken = 0;                       // accepted steps
  double max_rotation_deg = 0.0;             // largest change of a camera's orientation
  double max_shift_px = 0.0;  // largest image motion of a pixel at the view's depth (estimate)
};

// Refines cameras[v], the camera of views[v] (whose image is the target), against `model`.
// log_gain (views x 3, may be null) are the exposure codes the training renders are scaled by.
// views and cameras must have the same size; cameras keep their sizes.
CameraRefineStats RefineCameras(const TensorfModel& model, const std::vector<View>& views,
                                const float* log_gain, const CameraRefineOptions& options,
                                std::vector<Camera>* cameras);

// The cameras `moved` re-expressed by the similarity that best carries `before` onto `after`
// (same-size camera lists, the training cameras before and after refinement): held-out cameras
// posed with the training ones follow the training ones' common drift before they are refined
// themselves. Intrinsics are taken from after[0] when all of `after` share them.
std::vector<Camera> FollowRefinedCameras(const std::vector<Camera>& before,
                                         const std::vector<Camera>& after,
                                         const std::vector<Camera>& moved);

// The held-out cameras of `test` for scoring a field trained with refined cameras: first moved
// with the training cameras' common drift (FollowRefinedCameras from the views' own cameras to
// `refined`), then the poses of the views in `scored` (indices into test.views, as EvalViews
// gives them) refined against `model` on the left halves of their own images (exposure neutral;
// the intrinsics stay the refined shared ones): the right halves are what is scored, so no scored
// pixel fits the camera it is scored with. Views that are not scored only follow the drift:
// refining a camera costs about as much as rendering its view, and a run that scores 20 of 200
// held-out views should not pay for 200. Appends the alignment's statistics to stats_or_null.
std::vector<Camera> AlignHeldOutCameras(const TensorfModel& model, const Dataset& train,
                                        const Dataset& test, const std::vector<Camera>& refined,
                                        const std::vector<size_t>& scored, uint64_t seed,
                                        std::vector<CameraRefineStats>* stats_or_null);

// `data` with cameras[v] for view v, aligned to the left halves of their views as
// AlignHeldOutCameras does: each view's fitted_columns becomes width / 2, so that only the right
// half is scored (cameras empty: `data` unchanged).
Dataset WithCameras(Dataset data, const std::vector<Camera>& cameras);

// Whether every camera has the same size and intrinsics (one physical camera).
bool SharedIntrinsics(const std::vector<Camera>& cameras);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_CAMERA_REFINE_H_
