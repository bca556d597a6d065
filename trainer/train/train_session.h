// The state of one training run, shared by the step and the scheduled events (train_events.h):
// the model and its optimizers, the rays, the rate objective and its controller, the progress a
// checkpoint carries, the batch buffers and the result being filled in. It is set up fresh or
// from the run's checkpoint (--resume) in two stages, the model first and then the rest, in the
// order that keeps a resumed run equal to the uninterrupted one bit for bit.
#ifndef ECRF_TRAINER_TRAIN_TRAIN_SESSION_H_
#define ECRF_TRAINER_TRAIN_TRAIN_SESSION_H_

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "trainer/data/dataset.h"
#include "trainer/data/ray_set.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/quant_aware.h"
#include "trainer/rate/train_rate_control.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/rate_state.h"
#include "trainer/train/train_options.h"
#include "trainer/train/train_schedule.h"
#include "trainer/train/train_state.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace trainer {

using TrainClock = std::chrono::steady_clock;

// The model as training starts: initialised at options.voxels_init, or loaded from
// out_dir/checkpoint.ckpt when options.resume.
struct ModelStart {
  TrainClock::time_point started;  // the run's clock, started before a checkpoint is read
  int first_iter = 0;
  Checkpoint checkpoint;          // the checkpoint as read, for LoadTrainState (else empty)
  float resumed_lambda_e = 0.0f;  // > 0: rate control goes on from this lambda_e
};

// The grid resolution of about `voxels` cubic voxels over `box`.
std::array<int, 3> ResolutionFor(long voxels, const Aabb& box);

// Configures `rate` from the options and starts `model`. Throws std::invalid_argument when
// `train` has no views, std::runtime_error when there is no checkpoint to resume from.
ModelStart StartModel(const TrainOptions& options, const Dataset& train, TensorfModel* model,
                      RateState* rate);

struct TrainSession {
  // The rest of the setup around a started model: rays (filtered to the box unless the
  // checkpoint restored them), optimizers, exposure codes, cameras, regularizer weights and the
  // training state a resume restores. Throws std::invalid_argument for an exposure_codes or
  // refine_cameras value that is none of auto, on, off.
  TrainSession(const TrainOptions& options, const Dataset& train, const Dataset& test,
               TensorfModel* model, RateState* rate, ModelStart start);
  TrainSession(const TrainSession&) = delete;
  TrainSession& operator=(const TrainSession&) = delete;

  const TrainOptions& o;
  const Dataset& train;
  const Dataset& test;
  TensorfModel* model;
  RateState& rate;
  TrainOptions live;                             // options.lambda_e moves under rate control
  std::unique_ptr<LambdaController> controller;  // --target-size, from the rate phase on
  const int first_iter;
  const TrainClock::time_point started;
  const std::string checkpoint_path;  // empty without an output directory
  RaySet rays;
  TrainSchedule schedule;
  Optimizers opt;
  TrainProgress progress;
  QuantAwareModel qat;
  bool exposure_on = false;
  // The held-out views that are scored: with refined cameras only these are aligned.
  int scored_stride = 1;
  std::vector<size_t> scored_views;
  float tv_density = 0.f, tv_app = 0.f;  // total-variation weights at the start of the run
  float lr_factor = 1.f;                 // the learning rate's decay per iteration

  // The batch of the current iteration (views and gains only with exposure codes).
  std::vector<float> origins, dirs, rgb;
  std::vector<uint32_t> ray_views;
  std::vector<float> ray_gain, dl_dgain;
  TrainStepStats stats;  // of the latest step

  // The mean loss over the steps since the last progress line.
  double mse_sum = 0.0;
  int mse_count = 0;
  TrainClock::time_point interval_start;
  double eval_seconds = 0.0;  // evaluations of this process (not training time)
  // The latest checkpoint this process wrote: --checkpoint-minutes counts from it, and a stop
  // does not write the same iteration twice.
  TrainClock::time_point last_checkpoint = TrainClock::now();
  int last_checkpoint_done = -1;

  TrainResult result;

  // Training time of this process plus what the checkpoint had accumulated.
  double TrainSeconds() const;
  // The model with everything an exact resume needs (train_state.h), after `done` steps.
  void SaveCheckpoint(int done, double train_seconds);
};

// Divergence guards. One NaN reaches every parameter within a few steps and Adam never washes it
// out: training stops with an error naming the iteration and what became of the checkpoint.
bool AllFinite(const std::vector<float>& values);
[[noreturn]] void FailDiverged(int iteration, const std::string& what,
                               const std::string& checkpoint_path);
void CheckModelFinite(const TensorfModel& model, int iteration, const std::string& checkpoint_path);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_TRAIN_SESSION_H_
