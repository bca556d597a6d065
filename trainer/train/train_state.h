// The training state besides the model: optimizers, sampler, random generator, schedule
// position and time. Checkpoints carry it so that a resumed run continues bit for bit as the
// uninterrupted run would have (with --qat-refresh 1, the default: a longer refresh interval
// recomputes its cached decoded grids once at the resume).
#ifndef ECRF_TRAINER_TRAIN_TRAIN_STATE_H_
#define ECRF_TRAINER_TRAIN_TRAIN_STATE_H_

#include <random>
#include <string>
#include <utility>
#include <vector>

#include "trainer/data/camera.h"
#include "trainer/data/ray_set.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/train/adam.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/exposure_codes.h"
#include "trainer/train/rate_state.h"
#include "trainer/train/train_options.h"

namespace ecrf {
namespace trainer {

// One Adam per parameter group, and TensoRF's learning-rate decay factor.
struct Optimizers {
  Adam density, appearance, head;
  float lr_scale = 1.0f;
  void Reset(TensorfModel& m);
  void Step(TensorfModel& m, const TrainOptions& o);
};

struct TrainProgress {
  std::mt19937_64 rng;
  float l1_weight = 0.f;
  double train_seconds = 0.0;  // training time before this process, evaluation excluded
  std::vector<std::pair<double, double>> psnr_curve;  // (training minutes, test PSNR)
  ExposureCodes exposure;                             // per-image exposure codes (off: no views)
  // The training cameras as refined so far (--refine-cameras; empty when off): the rays are made
  // from these.
  std::vector<Camera> cameras;
};

// The state as checkpoint arrays plus a JSON object (Checkpoint::json), for SaveModelCheckpoint.
Checkpoint SaveTrainState(const Optimizers& opt, const RateState& rate, const RaySet& rays,
                          const TrainProgress& progress);

// Restores what SaveTrainState wrote from a whole checkpoint (`path` for errors). Returns false
// when the checkpoint has no training state (written before ecrf saved it): the caller then
// resumes approximately, as it used to.
bool LoadTrainState(const Checkpoint& checkpoint, const std::string& path, Optimizers* opt,
                    RateState* rate, RaySet* rays, TrainProgress* progress);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_TRAIN_STATE_H_
