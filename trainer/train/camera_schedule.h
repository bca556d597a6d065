// When training refines the cameras (--refine-cameras, --refine-cameras-every), and one round of
// it inside the training loop: the schedule is small steps interleaved with the field's, from
// kRefineCamerasFrom to kRefineCamerasUntil of the run (train_options.h), so that cameras and
// field settle together (docs/photos-to-dataset.md).
#ifndef ECRF_TRAINER_TRAIN_CAMERA_SCHEDULE_H_
#define ECRF_TRAINER_TRAIN_CAMERA_SCHEDULE_H_

#include <cstdint>
#include <vector>

#include "trainer/data/dataset.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/train/camera_refine.h"
#include "trainer/train/train_options.h"

namespace ecrf {
namespace trainer {

// Whether --refine-cameras is on for this dataset ("auto": when its poses were estimated).
// std::invalid_argument for a value other than auto, on, off.
bool RefineCamerasOn(const TrainOptions& options, const Dataset& train);

struct CameraRefineSchedule {
  bool on = false;
  int every = 1;  // iterations between rounds
  int from = 0;   // first round after this many iterations
  int until = 0;  // no round after this many
  // Whether a round follows iteration `done` (1-based count of iterations done).
  bool Due(int done) const;
};

CameraRefineSchedule CameraRefineScheduleFor(const TrainOptions& options, const Dataset& train);

// One round (one Levenberg-Marquardt step of RefineCameras) after iteration `done`: refines
// `cameras` (those of `views`) against `model`, appends its statistics to `log` and prints a line
// every 10th round and at the last.
void RefineCamerasRound(int done, const CameraRefineSchedule& schedule, const TensorfModel& model,
                        const std::vector<View>& views, const float* log_gain, uint64_t seed,
                        std::vector<Camera>* cameras, std::vector<CameraRefineStats>* log);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_CAMERA_SCHEDULE_H_
