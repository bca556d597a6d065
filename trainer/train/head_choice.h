// --head auto: the appearance head and the sample spacing chosen by what a view of the scene
// will cost. Once the grid is final (after the last upsample and alpha-mask update: the samples
// and coloured samples per ray are then the file's), the trainer traces training rays through
// the model, predicts the work per pixel of each candidate in the decoder's units
// (decoder/render_work.h) and takes the first, in the order of expected quality, within the
// render budget (--render-budget, --device-class): the per-sample head, the deferred head, the
// deferred head at twice the spacing (--step-ratio), then the deferred head with
// spherical-harmonics colour (--sh-degree) at the spacing and at twice it; the cheapest when none
// is. The deferred head's MLP starts from the per-sample one's weights (for an opaque surface the
// weighted sum of the products is about the surface's products, the per-sample head's input);
// the harmonics start afresh (no MLP to start from) and train on with the grids. Without a budget
// auto keeps the per-sample head: on chair it has the better rate-distortion (docs/results.md).
#ifndef ECRF_TRAINER_TRAIN_HEAD_CHOICE_H_
#define ECRF_TRAINER_TRAIN_HEAD_CHOICE_H_

#include <cstdint>
#include <string>
#include <vector>

#include "format/mlp_coder.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/train/train_options.h"

namespace ecrf {
namespace trainer {

// What a ray of the model costs, averaged over the traced rays.
struct RayWorkCounts {
  double samples = 0.0;        // evaluated samples (inside the box and the mask)
  double coloured = 0.0;       // of them coloured (weight above the threshold)
  double coloured_rays = 0.0;  // share of the rays with a coloured sample
};

// Traces n rays (origins, dirs: n x 3) through the model as the decoder's reference process
// samples them (no jitter).
RayWorkCounts CountRayWork(const TensorfModel& model, int n, const float* origins,
                           const float* dirs);

// The predicted work per pixel of each head for these counts (marched positions taken as the
// evaluated samples: a lower bound where the mask rejects samples), indexed by HeadKind; with
// `head` the widths of another head on the model's grids (the model's own by default).
std::vector<double> PredictHeadWork(const TensorfModel& model, const RayWorkCounts& counts,
                                    const AppearanceHeadConfig* head = nullptr);

// The render budget the options ask for (--render-budget, else --device-class; 0: none).
double RenderBudget(const TrainOptions& options);

// One configuration auto weighs: a head at a sample spacing, with the counts traced at that
// spacing and the predicted work per pixel.
struct RenderCandidate {
  HeadKind head = HeadKind::kPerSample;
  float step_ratio = 0.5f;
  int sh_degree = -1;  // >= 0: spherical-harmonics colour of this degree in place of the MLP
  RayWorkCounts counts;
  double work = 0.0;
};

// The candidates for a model in the order of expected quality: each head at the model's
// spacing, then the deferred head at twice it, then with sh_degree >= 0 the deferred head with
// harmonics of that degree at both spacings. Traces the n rays once per spacing (the model's
// spacing is restored).
std::vector<RenderCandidate> RenderCandidates(TensorfModel* model, int n, const float* origins,
                                              const float* dirs, int sh_degree = -1);

struct HeadChoiceReport {
  int iteration = -1;  // -1: no choice was made in this run
  double budget = 0.0;
  std::vector<RenderCandidate> candidates;
  int chosen = 0;  // index into candidates
  std::string reason;
  const RenderCandidate& choice() const { return candidates[size_t(chosen)]; }
};

// The first candidate within the budget (the first when there is no budget), else the cheapest.
HeadChoiceReport ChooseRender(std::vector<RenderCandidate> candidates, double budget);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_HEAD_CHOICE_H_
