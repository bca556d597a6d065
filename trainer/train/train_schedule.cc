#include "trainer/train/train_schedule.h"

#include <algorithm>
#include <cmath>

namespace ecrf {
namespace trainer {

int GridFinalIteration(const TrainOptions& o) {
  int final_it = 0;
  for (int m : o.upsample_iters)
    final_it = std::max(final_it, ScaleMilestone(m, o.iters, o.reference_iters) + 1);
  for (int m : o.alpha_mask_iters)
    final_it = std::max(final_it, ScaleMilestone(m, o.iters, o.reference_iters) + 1);
  return final_it;
}

bool UsesRateObjective(const TrainOptions& o) { return o.lambda_e > 0.0f || o.target_bytes > 0; }

std::vector<int> ScaledMilestones(const std::vector<int>& milestones, const TrainOptions& o) {
  std::vector<int> at;
  for (int m : milestones) at.push_back(ScaleMilestone(m, o.iters, o.reference_iters));
  return at;
}

int RateStartIteration(const TrainOptions& o) {
  return std::max(int(std::lround(double(o.rate_start) * o.iters)), GridFinalIteration(o));
}

int QatStartIteration(const TrainOptions& o) {
  if (o.qat_start < 0.0f) {
    return UsesRateObjective(o) ? std::min(RateStartIteration(o), o.iters) : o.iters;
  }
  if (!(o.qat_start < 1.0f)) return o.iters;
  int start = int(std::lround(double(std::max(0.0f, o.qat_start)) * o.iters));
  // The steps freeze when quantization-aware training starts, so it waits for the final grid
  // shape and the rate phase (whose steps it shares).
  start = std::max(start, RateStartIteration(o));
  return std::min(start, o.iters);
}

namespace {

std::vector<size_t> IndicesOf(const std::vector<int>& milestones, int it) {
  std::vector<size_t> due;
  for (size_t k = 0; k < milestones.size(); ++k)
    if (milestones[k] == it) due.push_back(k);
  return due;
}

}  // namespace

std::vector<size_t> TrainSchedule::MaskUpdatesAt(int it) const { return IndicesOf(mask_at, it); }

std::vector<size_t> TrainSchedule::UpsamplesAt(int it) const { return IndicesOf(upsample_at, it); }

bool TrainSchedule::RateControlDue(int it) const {
  return it > rate_start && (it - rate_start) % std::max(1, options.rate_control_every) == 0;
}

bool TrainSchedule::QatRefreshDue(int it) const {
  return (it - qat_start) % std::max(1, options.qat_refresh) == 0;
}

bool TrainSchedule::PruneDue(int done) const {
  const TrainOptions& o = options;
  for (float share : o.prune_at) {
    const int at = rate_start + static_cast<int>(std::lround(share * (o.iters - rate_start)));
    if (done == at && done > rate_start && done < o.iters) return true;
  }
  return false;
}

bool TrainSchedule::ProgressDue(int done) const {
  return done % options.progress_every == 0 || done == options.iters;
}

bool TrainSchedule::EvalDue(int done) const {
  return options.eval_every > 0 && done % options.eval_every == 0 && done < options.iters;
}

bool TrainSchedule::CheckpointDue(int done) const {
  return !options.out_dir.empty() && options.checkpoint_every > 0 &&
         done % options.checkpoint_every == 0 && done < options.iters;
}

bool TrainSchedule::StopDue(int done) const {
  return options.stop_after > 0 && done == options.stop_after && done < options.iters;
}

TrainSchedule ScheduleFor(const TrainOptions& o, const Dataset& train) {
  TrainSchedule s;
  s.options = o;
  s.use_rate = UsesRateObjective(o);
  s.rate_start = RateStartIteration(o);
  s.qat_start = QatStartIteration(o);
  s.grid_final = GridFinalIteration(o);
  s.upsample_at = ScaledMilestones(o.upsample_iters, o);
  s.mask_at = ScaledMilestones(o.alpha_mask_iters, o);
  s.voxel_counts = UpsampleVoxelCounts(o);
  s.cameras = CameraRefineScheduleFor(o, train);
  return s;
}

}  // namespace trainer
}  // namespace ecrf
