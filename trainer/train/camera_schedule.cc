#include "trainer/train/camera_schedule.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "trainer/data/seconds_since.h"

namespace ecrf {
namespace trainer {

bool RefineCamerasOn(const TrainOptions& o, const Dataset& train) {
  return IsOn(o.refine_cameras, train.estimated_poses);
}

bool CameraRefineSchedule::Due(int done) const {
  return on && done >= from && done <= until && (done - from) % every == 0;
}

CameraRefineSchedule CameraRefineScheduleFor(const TrainOptions& o, const Dataset& train) {
  CameraRefineSchedule s;
  s.on = RefineCamerasOn(o, train);
  s.every = o.refine_cameras_every > 0 ? o.refine_cameras_every : std::max(1, o.iters / 50);
  s.from = int(std::lround(
      (train.warmed_up_cameras ? kRefineCamerasFromWarmedUp : kRefineCamerasFrom) * o.iters));
  s.until = int(std::lround(kRefineCamerasUntil * o.iters));
  return s;
}

void RefineCamerasRound(int done, const CameraRefineSchedule& schedule, const TensorfModel& model,
                        const std::vector<View>& views, const float* log_gain, uint64_t seed,
                        std::vector<Camera>* cameras, std::vector<CameraRefineStats>* log) {
  const auto start = std::chrono::steady_clock::now();
  CameraRefineOptions ro;
  ro.seed = seed;
  ro.pixels_per_view = 256;
  ro.steps = 1;
  const CameraRefineStats s = RefineCameras(model, views, log_gain, ro, cameras);
  log->push_back(s);
  const int round = (done - schedule.from) / schedule.every;
  if (round % 10 == 0 || done + schedule.every > schedule.until) {
    const double seconds = SecondsSince(start);
    std::fprintf(stderr,
                 "%scameras refined (round %d) at iteration %d: pixel error %.5f -> %.5f (%d "
                 "steps), largest change %.3f deg, ~%.2f px; %.1f s\n",
                 isatty(2) ? "\n" : "", round + 1, done, s.mse_before, s.mse_after, s.steps_taken,
                 s.max_rotation_deg, s.max_shift_px, seconds);
  }
}

}  // namespace trainer
}  // namespace ecrf
