// When each event of a training run is due: the milestones of TensoRF's schedule scaled to the
// run's length, the rate phase and quantization-aware training, rate control, pruning, camera
// refinement rounds, progress lines, evaluations, checkpoints and --stop-after. Pure functions of
// the options (and, for the cameras, of the training views), so that the schedule is tested
// without training; the events themselves are in train_events.h.
#ifndef ECRF_TRAINER_TRAIN_TRAIN_SCHEDULE_H_
#define ECRF_TRAINER_TRAIN_TRAIN_SCHEDULE_H_

#include <cstddef>
#include <vector>

#include "trainer/data/dataset.h"
#include "trainer/train/camera_schedule.h"
#include "trainer/train/train_options.h"

namespace ecrf {
namespace trainer {

// Milestones of the preset's schedule (o.upsample_iters, o.alpha_mask_iters) scaled to this run.
std::vector<int> ScaledMilestones(const std::vector<int>& milestones, const TrainOptions& options);
// The first iteration after the last upsample and alpha-mask update (0 without them): from it on
// the grid has its final shape (and --head auto chooses, head_choice.h).
int GridFinalIteration(const TrainOptions& options);
// Whether the rate objective is asked for: lambda_e > 0 or a target size.
bool UsesRateObjective(const TrainOptions& options);
// The iteration at which the rate terms switch on: options.rate_start of the run, but never
// before the grid is final.
int RateStartIteration(const TrainOptions& options);
// The iteration quantization-aware training starts at (options.iters: never); never before the
// rate phase.
int QatStartIteration(const TrainOptions& options);

// Iterations are counted from 0: "at `it`" is the step of iteration it (before it, or right
// after it for the grid milestones, as in TensoRF's train.py); "after `done`" counts the steps
// done (it + 1), the unit of --checkpoint-every, --eval-every and --stop-after.
struct TrainSchedule {
  TrainOptions options;
  bool use_rate = false;  // the rate objective is asked for (lambda_e > 0 or a target size)
  int rate_start = 0;     // RateStartIteration
  int qat_start = 0;      // QatStartIteration
  int grid_final = 0;     // GridFinalIteration
  std::vector<int> upsample_at, mask_at;  // the milestones scaled to this run
  std::vector<long> voxel_counts;         // the grid's voxels after each upsample
  CameraRefineSchedule cameras;

  // The indices of the alpha-mask updates (of mask_at) and of the upsamples (of upsample_at)
  // after the step of iteration `it`, in order (two milestones a short run scales onto one
  // iteration both run).
  std::vector<size_t> MaskUpdatesAt(int it) const;
  std::vector<size_t> UpsamplesAt(int it) const;
  // Whether iteration `it` is in the rate phase (the rate objective asked for and started).
  bool InRatePhase(int it) const { return use_rate && it >= rate_start; }
  // Whether the rate controller (--target-size) measures the file before iteration `it`: every
  // rate_control_every iterations of the rate phase, not at its first.
  bool RateControlDue(int it) const;
  // Whether iteration `it` steps the quantized grids.
  bool QuantAware(int it) const { return it >= qat_start; }
  // Whether the quantized grids are recomputed before iteration `it` (every qat_refresh
  // iterations from qat_start; the trainer also refreshes them when the shapes change).
  bool QatRefreshDue(int it) const;
  // Whether a pruning test follows `done` steps: the shares of --prune-at count from the start
  // of the rate phase (the bits of a component are only weighed there) to the end of the run.
  bool PruneDue(int done) const;
  bool ProgressDue(int done) const;    // a progress line (and always after the last step)
  bool EvalDue(int done) const;        // a point of the test PSNR curve, not at the end
  bool CheckpointDue(int done) const;  // with an output directory; the end writes its own
  bool StopDue(int done) const;        // --stop-after, unless the run ends there anyway
};

// std::invalid_argument when options.refine_cameras is none of auto, on, off.
TrainSchedule ScheduleFor(const TrainOptions& options, const Dataset& train);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_TRAIN_SCHEDULE_H_
