// When each event of a training run is due (trainer/train/train_schedule.h), from the options
// alone: no training.
#include "trainer/train/train_schedule.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace ecrf {
namespace trainer {
namespace {

// The tiny preset (milestones stated for 1,500 iterations) shortened to 120: upsamples at 16,
// 32, 48, 64 and alpha-mask updates at 24, 56.
TrainOptions ShortTinyRun() {
  TrainOptions o = PresetOptions("tiny");
  o.iters = 120;
  return o;
}

// The values from..to (iterations or steps done) at which `due` holds.
std::vector<int> Where(int from, int to, bool (TrainSchedule::*due)(int) const,
                       const TrainSchedule& s) {
  std::vector<int> at;
  for (int i = from; i <= to; ++i)
    if ((s.*due)(i)) at.push_back(i);
  return at;
}

TEST(TrainSchedule, GridMilestonesScaleToTheRunAndFollowTheirIteration) {
  const TrainSchedule s = ScheduleFor(ShortTinyRun(), Dataset());
  EXPECT_EQ(s.upsample_at, (std::vector<int>{16, 32, 48, 64}));
  EXPECT_EQ(s.mask_at, (std::vector<int>{24, 56}));
  ASSERT_EQ(s.voxel_counts.size(), 4u);
  EXPECT_EQ(s.voxel_counts.back(), 96L * 96 * 96);
  EXPECT_EQ(s.MaskUpdatesAt(24), (std::vector<size_t>{0}));
  EXPECT_EQ(s.MaskUpdatesAt(56), (std::vector<size_t>{1}));
  EXPECT_TRUE(s.MaskUpdatesAt(25).empty());
  EXPECT_TRUE(s.MaskUpdatesAt(0).empty());
  EXPECT_EQ(s.UpsamplesAt(16), (std::vector<size_t>{0}));
  EXPECT_EQ(s.UpsamplesAt(64), (std::vector<size_t>{3}));
  EXPECT_TRUE(s.UpsamplesAt(24).empty());

  // A run so short that two milestones scale onto one iteration runs both, in order.
  TrainOptions o = ShortTinyRun();
  o.iters = 4;  // upsamples at 200, 400, 600, 800 of 1,500: 1, 1, 2, 2; masks 1 and 2
  const TrainSchedule t = ScheduleFor(o, Dataset());
  EXPECT_EQ(t.UpsamplesAt(1), (std::vector<size_t>{0, 1}));
  EXPECT_EQ(t.UpsamplesAt(2), (std::vector<size_t>{2, 3}));
  EXPECT_EQ(t.MaskUpdatesAt(1), (std::vector<size_t>{0}));
  EXPECT_EQ(t.MaskUpdatesAt(2), (std::vector<size_t>{1}));
}

TEST(TrainSchedule, RatePhaseAndQuantAwareStepsStartAfterTheLastMilestone) {
  TrainOptions o = ShortTinyRun();
  const TrainSchedule plain = ScheduleFor(o, Dataset());
  EXPECT_FALSE(plain.use_rate);
  EXPECT_FALSE(plain.InRatePhase(119));
  EXPECT_FALSE(plain.QuantAware(119));  // no rate objective: no quantization-aware steps

  o.lambda_e = 1e-9f;  // rate_start 16/30 of 120 = 64, pushed after the last upsample at 64
  const TrainSchedule s = ScheduleFor(o, Dataset());
  EXPECT_EQ(s.rate_start, 65);
  EXPECT_EQ(s.qat_start, 65);  // by default with the rate phase
  EXPECT_FALSE(s.InRatePhase(64));
  EXPECT_TRUE(s.InRatePhase(65));
  EXPECT_FALSE(s.QuantAware(64));
  EXPECT_TRUE(s.QuantAware(65));

  o.lambda_e = 0.f;
  o.target_bytes = 50000;  // a target size is a rate objective too
  o.qat_start = 0.8f;
  const TrainSchedule t = ScheduleFor(o, Dataset());
  EXPECT_TRUE(t.InRatePhase(65));
  EXPECT_EQ(t.qat_start, 96);
  EXPECT_FALSE(t.QuantAware(95));
}

TEST(TrainSchedule, RateControlAndQatRefreshRecurFromTheirStart) {
  TrainOptions o = ShortTinyRun();
  o.target_bytes = 50000;
  o.rate_control_every = 20;
  o.qat_refresh = 10;
  o.qat_start = 0.8f;
  const TrainSchedule s = ScheduleFor(o, Dataset());
  // Not at the rate phase's first iteration: the controller has measured nothing yet.
  EXPECT_EQ(Where(0, o.iters - 1, &TrainSchedule::RateControlDue, s), (std::vector<int>{85, 105}));
  std::vector<int> refresh;
  for (int it = s.qat_start; it < o.iters; ++it)
    if (s.QatRefreshDue(it)) refresh.push_back(it);
  EXPECT_EQ(refresh, (std::vector<int>{96, 106, 116}));
  o.rate_control_every = 0;  // read as every iteration
  EXPECT_TRUE(ScheduleFor(o, Dataset()).RateControlDue(66));
}

TEST(TrainSchedule, PruningSharesCountFromTheRatePhaseToTheEnd) {
  TrainOptions o = ShortTinyRun();
  o.lambda_e = 1e-9f;                   // rate phase from 65: 55 iterations
  o.prune_at = {0.4f, 0.f, 1.f, 0.6f};  // the phase's first and last steps are never tested
  const TrainSchedule s = ScheduleFor(o, Dataset());
  EXPECT_EQ(Where(1, o.iters, &TrainSchedule::PruneDue, s), (std::vector<int>{65 + 22, 65 + 33}));
}

TEST(TrainSchedule, ProgressEvaluationsCheckpointsAndStopsCountStepsDone) {
  TrainOptions o = ShortTinyRun();
  o.progress_every = 50;
  o.eval_every = 40;
  o.checkpoint_every = 60;
  o.stop_after = 70;
  const TrainSchedule s = ScheduleFor(o, Dataset());
  // The last step always reports; the end of the run evaluates and checkpoints on its own.
  EXPECT_EQ(Where(1, o.iters, &TrainSchedule::ProgressDue, s), (std::vector<int>{50, 100, 120}));
  EXPECT_EQ(Where(1, o.iters, &TrainSchedule::EvalDue, s), (std::vector<int>{40, 80}));
  EXPECT_TRUE(Where(1, o.iters, &TrainSchedule::CheckpointDue, s).empty())
      << "no output directory, no checkpoint";
  EXPECT_EQ(Where(1, o.iters, &TrainSchedule::StopDue, s), (std::vector<int>{70}));

  o.out_dir = "run";
  EXPECT_EQ(Where(1, o.iters, &TrainSchedule::CheckpointDue, ScheduleFor(o, Dataset())),
            (std::vector<int>{60}));
  o.stop_after = 120;  // the run ends there anyway
  o.eval_every = 0;
  o.checkpoint_every = 0;
  const TrainSchedule off = ScheduleFor(o, Dataset());
  EXPECT_TRUE(Where(1, o.iters, &TrainSchedule::StopDue, off).empty());
  EXPECT_TRUE(Where(1, o.iters, &TrainSchedule::EvalDue, off).empty());
  EXPECT_TRUE(Where(1, o.iters, &TrainSchedule::CheckpointDue, off).empty());
}

TEST(TrainSchedule, CameraRoundsOnlyForRefinedCamerasBetweenTheirShares) {
  TrainOptions o = ShortTinyRun();
  Dataset rendered, estimated;
  estimated.estimated_poses = true;
  EXPECT_FALSE(ScheduleFor(o, rendered).cameras.on);  // auto: exact cameras stay
  const TrainSchedule s = ScheduleFor(o, estimated);
  ASSERT_TRUE(s.cameras.on);
  std::vector<int> rounds;
  for (int done = 1; done <= o.iters; ++done)
    if (s.cameras.Due(done)) rounds.push_back(done);
  // Every iters / 50 = 2 steps from 0.2 to 0.8 of the run.
  ASSERT_FALSE(rounds.empty());
  EXPECT_EQ(rounds.front(), 24);
  EXPECT_EQ(rounds.back(), 96);
  EXPECT_EQ(rounds.size(), size_t((96 - 24) / 2 + 1));
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
