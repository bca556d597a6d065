// --head auto: the appearance head chosen by what a view of the scene will cost. Once the grid is
// final (after the last upsample and alpha-mask update: the samples and coloured samples per ray
// are then the file's), the trainer traces training rays through the model, predicts each head's
// work per pixel in the decoder's units (decoder/render_work.h) and keeps the per-sample head
// unless it exceeds the render budget (--render-budget, --device-class); then it continues with
// the deferred head, whose MLP starts from the per-sample one's weights (for an opaque surface
// the weighted sum of the products is about the surface's products, the per-sample head's input).
// Without a budget auto keeps the per-sample head: on chair it has the better rate-distortion
// (docs/results.md).
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
// evaluated samples: a lower bound where the mask rejects samples), indexed by HeadKind.
std::vector<double> PredictHeadWork(const TensorfModel& model, const RayWorkCounts& counts);

// The render budget the options ask for (--render-budget, else --device-class; 0: none).
double RenderBudget(const TrainOptions& options);

struct HeadChoiceReport {
  int iteration = -1;  // -1: no choice was made in this run
  double budget = 0.0;
  RayWorkCounts counts;
  std::vector<double> work;  // per HeadKind
  HeadKind chosen = HeadKind::kPerSample;
  std::string reason;
};

// The choice for a model: the per-sample head unless its predicted work exceeds the budget.
HeadChoiceReport ChooseHead(const TensorfModel& model, const RayWorkCounts& counts, double budget);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_HEAD_CHOICE_H_
