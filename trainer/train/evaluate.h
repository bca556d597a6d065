// Scoring the float model on held-out views: renders them and compares with their images.
#ifndef ECRF_TRAINER_TRAIN_EVALUATE_H_
#define ECRF_TRAINER_TRAIN_EVALUATE_H_

#include <string>
#include <vector>

#include "trainer/data/dataset.h"
#include "trainer/data/image_io.h"
#include "trainer/model/tensorf_model.h"

namespace ecrf {
namespace trainer {

struct EvalResult {
  double psnr = 0.0;  // mean over views
  double ssim = 0.0;  // mean over views
  int views = 0;
  int width = 0, height = 0;     // the scored images' size (the first view's), for the record
  int fitted_columns = 0;        // > 0: the half-image protocol (View::fitted_columns) scored them
  bool exposure_fitted = false;  // each view's gain fitted on its left half (View::fit_exposure)
  double seconds_per_view = 0.0;
  // Density and MLP evaluations per ray (what bounds render time), where the renderer counts them.
  double samples_per_ray = 0.0;
  double color_samples_per_ray = 0.0;  // coloured samples (the MLP's with the per-sample head)
  // The decoder's work per pixel, in the units of its render work budget (decoder/render_work.h:
  // multiply-adds of the MLP, the other steps at their measured time): the speed of the file.
  double work_per_pixel = 0.0;
  std::vector<Image> renders;  // filled when requested
};

// Adds one view's render to r's sums: PSNR (capped at 100 dB, so that one exact view cannot swamp
// the mean) and SSIM against the view's image over the columns it scores (the half-image
// protocol: View::fitted_columns are not), the view count, and the first view's size.
void AddViewScore(const Image& render, const View& view, EvalResult* r);

// The gain per channel that best maps `render` to `truth` over columns [0, x1) in least squares
// (sum render * truth / sum render^2; 1 where the render is black there).
void FitExposureGain(const Image& render, const Image& truth, int x1, float gain[3]);

// `data` with every view marked for the half-image protocol's exposure fit: the gain fitted on the
// left half, the right half scored (View::fit_exposure; fitted_columns at least half the width).
Dataset WithExposureFit(Dataset data);

// How views were scored, for what a run prints and records: "whole views", or the half-image
// protocol naming what the left halves fitted (cameras_aligned: the views' cameras were aligned).
std::string HeldOutScoring(const EvalResult& r, bool cameras_aligned);

// Renders every stride-th view of `test` (at most max_views, 0: all) and compares it with its
// image.
EvalResult Evaluate(const TensorfModel& model, const Dataset& test, int stride, int max_views,
                    bool keep_renders);

Image RenderView(const TensorfModel& model, const Camera& camera);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_EVALUATE_H_
