// The training loop's step and scheduled events (trainer/train/train_events.h), each on a tiny
// run of the built-in scene: an event does its work at the iteration it is due and nothing at
// the others. The end-to-end runs (train_builtin_test.cc) check the loop as a whole, resumes
// included.
#include "trainer/train/train_events.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "format/vm_modes.h"
#include "tests/common/scoped_temp_dir.h"
#include "tests/common/tiny_run.h"
#include "trainer/model/alpha_mask.h"
#include "trainer/rate/train_rate_control.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace trainer {
namespace {

// The tiny preset shortened to 120 iterations (upsamples at 16, 32, 48, 64, alpha-mask updates
// at 24, 56) on 8 views of 32 x 32 pixels.
TrainOptions TinyRun() {
  TrainOptions o = testing_runs::TinyBuiltinRun(32, 8, 120);  // no progress lines unless asked
  o.batch_rays = 512;
  return o;
}

// A session set up as Train sets it up (fresh, or resumed when the options say so).
struct TinySession {
  explicit TinySession(const TrainOptions& o)
      : o(o),
        train(LoadTrainingViews(o, "train")),
        test(LoadTrainingViews(o, "test")),
        model(ConfigFor(o, train)),
        s(this->o, train, test, &model, &rate, StartModel(this->o, train, &model, &rate)) {}

  // The iterations from the last one run up to `end` (excluded), events included.
  void RunUntil(int end) {
    for (; next < end; ++next) RunIteration(s, next);
  }

  const TrainOptions o;
  const Dataset train, test;
  TensorfModel model;
  RateState rate;
  int next = 0;
  TrainSession s;  // last: it holds references to the members above
};

double Volume(const Aabb& b) {
  return double(b.max[0] - b.min[0]) * (b.max[1] - b.min[1]) * (b.max[2] - b.min[2]);
}

// A density of 300 (before the shift) inside the middle half of the grid along every axis and 0
// outside: component 0 of each mode is 10 on the middle half of its plane and of its line.
void MakeDensityCube(TensorfModel* model) {
  VmGrid& g = model->density();
  std::fill(g.params().begin(), g.params().end(), 0.f);
  const std::array<int, 3>& res = g.res();
  auto inside = [&res](int axis, int i) { return i >= res[axis] / 4 && i < res[axis] * 3 / 4; };
  for (int m = 0; m < 3; ++m) {
    const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
    for (int y = 0; y < res[v]; ++y)
      for (int x = 0; x < res[u]; ++x)
        if (inside(v, y) && inside(u, x)) g.PlaneAt(m, y, x, 0) = 10.f;
    for (int i = 0; i < res[w]; ++i)
      if (inside(w, i)) g.LineAt(m, i, 0) = 10.f;
  }
}

int ComponentCount(const TensorfModel& m) {
  const auto& d = m.density().ranks();
  const auto& a = m.appearance().ranks();
  return d[0] + d[1] + d[2] + a[0] + a[1] + a[2];
}

TEST(TrainSession, StartsFreshAtTheInitialGridAndResumesOnlyFromACheckpoint) {
  TinySession r(TinyRun());
  EXPECT_EQ(r.s.first_iter, 0);
  EXPECT_EQ(r.s.model->res(), (std::array<int, 3>{32, 32, 32}));  // voxels_init 32^3, a cube
  EXPECT_LE(r.s.rays.size(), r.s.rays.total());                   // filtered to the box
  EXPECT_FALSE(r.s.exposure_on);                                  // auto: an object scene has none
  EXPECT_EQ(r.s.progress.l1_weight, r.s.o.l1_weight_initial);

  TrainOptions o = TinyRun();
  o.resume = true;  // without an output directory there is nothing to resume from
  EXPECT_THROW(TinySession{o}, std::runtime_error);
}

TEST(TrainEvents, StepDrawsABatchMovesTheParametersAndDecaysTheLearningRate) {
  TinySession r(TinyRun());
  TrainSession& s = r.s;
  const std::vector<float> before = s.model->density().params();
  DrawBatch(s);
  EXPECT_NE(std::accumulate(s.rgb.begin(), s.rgb.end(), 0.0), 0.0);
  OptimizeStep(s, 0);
  EXPECT_NE(s.model->density().params(), before);
  EXPECT_EQ(s.opt.density.step_count(), 1);
  EXPECT_EQ(s.opt.lr_scale, s.lr_factor);
  EXPECT_EQ(s.mse_count, 1);
  EXPECT_GT(s.mse_sum, 0.0);
}

TEST(TrainEvents, ProgressLinesAverageTheStepsSinceTheLast) {
  TrainOptions o = TinyRun();
  o.progress_every = 2;
  TinySession r(o);
  TrainSession& s = r.s;
  double sum = 0.0;
  for (int it = 0; it < 2; ++it) {
    DrawBatch(s);
    OptimizeStep(s, it);
    sum += s.stats.mse;
    ReportProgress(s, it);
    if (it == 0) EXPECT_EQ(s.mse_count, 1) << "no line after one step of two";
  }
  EXPECT_EQ(s.mse_count, 0);
  EXPECT_DOUBLE_EQ(s.result.final_train_psnr, -10.0 * std::log10(sum / 2));
}

TEST(TrainEvents, FirstAlphaMaskUpdateShrinksTheBoxTheSecondFiltersTheRays) {
  TinySession r(TinyRun());
  TrainSession& s = r.s;
  r.RunUntil(1);  // the optimizers have stepped
  MakeDensityCube(s.model);
  const Aabb box = s.model->aabb();
  const size_t rays = s.rays.size();
  UpdateAlphaMask(s, 25);
  EXPECT_EQ(s.model->alpha_mask(), nullptr) << "not due";
  EXPECT_EQ(s.opt.density.step_count(), 1);

  UpdateAlphaMask(s, 24);
  ASSERT_NE(s.model->alpha_mask(), nullptr);
  // The middle half of the box along each axis, with the mask's one-vertex margin.
  EXPECT_LT(Volume(s.model->aabb()), 0.25 * Volume(box));
  for (int a = 0; a < 3; ++a) {
    EXPECT_GT(s.model->aabb().min[a], box.min[a]);
    EXPECT_LT(s.model->aabb().max[a], box.max[a]);
  }
  EXPECT_EQ(s.progress.l1_weight, s.o.l1_weight_rest);
  EXPECT_EQ(s.opt.density.step_count(), 0);  // the grids' shapes changed
  EXPECT_EQ(s.opt.density.size(), s.model->density().params().size());
  EXPECT_EQ(s.rays.size(), rays);

  DrawBatch(s);
  OptimizeStep(s, 24);
  const Aabb shrunk = s.model->aabb();
  UpdateAlphaMask(s, 56);
  EXPECT_LT(s.rays.size(), rays);  // only the rays through the cube train on
  EXPECT_GT(s.rays.size(), size_t(s.o.batch_rays));
  EXPECT_EQ(s.opt.density.step_count(), 1);
  EXPECT_EQ(Volume(s.model->aabb()), Volume(shrunk));
}

// When training ends the mask comes from the trained density, on the last update's points (or,
// with --mask-downscale, on the coarsened grid's as every update): a density that has contracted
// since that update leaves the space it gave up unmasked.
TEST(TrainEvents, TheFinalAlphaMaskComesFromTheTrainedDensity) {
  struct Case {
    bool keep_last;
    int downscale;
  };
  for (const Case c : {Case{false, 1}, Case{true, 1}, Case{false, 2}}) {
    SCOPED_TRACE(std::string(c.keep_last ? "kept" : "refreshed") + ", downscale " +
                 std::to_string(c.downscale));
    TrainOptions o = TinyRun();
    o.keep_last_mask = c.keep_last;
    o.mask_downscale = c.downscale;
    TinySession r(o);
    TrainSession& s = r.s;
    r.RunUntil(1);
    MakeDensityCube(s.model);
    UpdateAlphaMask(s, 24);  // shrinks the box to the cube
    UpdateAlphaMask(s, 56);  // a mask of the shrunk box, nearly full
    UpsampleGrids(s, 32);
    MakeDensityCube(s.model);  // the density now holds the middle half of the shrunk box
    const AlphaMask last = *s.model->alpha_mask();
    RefreshAlphaMask(s);
    const AlphaMask& mask = *s.model->alpha_mask();
    if (c.keep_last) {
      EXPECT_EQ(mask.occupancy(), last.occupancy());
      continue;
    }
    EXPECT_EQ(mask.res(), c.downscale == 1 ? last.res() : AlphaMaskRes(s.model->res(), 2));
    EXPECT_LT(double(mask.count()) / double(mask.occupancy().size()),
              0.5 * double(last.count()) / double(last.occupancy().size()));
    const Aabb& b = s.model->aabb();
    auto point = [&b](float f) {  // f of the way along each axis of the box
      std::array<float, 3> p;
      for (int a = 0; a < 3; ++a) p[a] = b.min[a] + f * (b.max[a] - b.min[a]);
      return p;
    };
    for (float f : {0.3f, 0.5f, 0.7f}) EXPECT_TRUE(mask.Occupied(point(f).data())) << f;
    for (float f : {0.02f, 0.98f}) {
      EXPECT_TRUE(last.Occupied(point(f).data())) << f;
      EXPECT_FALSE(mask.Occupied(point(f).data())) << f;
    }
  }
}

TEST(TrainEvents, UpsampleReachesTheNextVoxelCountAndResetsTheOptimizers) {
  TinySession r(TinyRun());
  TrainSession& s = r.s;
  r.RunUntil(1);
  const std::array<int, 3> res = s.model->res();
  UpsampleGrids(s, 15);
  EXPECT_EQ(s.model->res(), res);
  UpsampleGrids(s, 16);
  EXPECT_EQ(s.model->res(), ResolutionFor(s.schedule.voxel_counts[0], s.model->aabb()));
  EXPECT_GT(s.model->res()[0], res[0]);
  EXPECT_EQ(s.opt.density.step_count(), 0);
  EXPECT_EQ(s.opt.density.size(), s.model->density().params().size());
}

TEST(TrainEvents, RatePhaseStartsTheObjectiveAndRateControlMovesLambda) {
  TrainOptions o = TinyRun();
  o.target_bytes = 1000;  // far below what a 32^3 grid costs: lambda_e must rise
  o.rate_control_every = 5;
  TinySession r(o);
  TrainSession& s = r.s;
  const int start = s.schedule.rate_start;
  StartRatePhase(s, start - 1);
  EXPECT_FALSE(s.rate.active);
  EXPECT_EQ(s.controller, nullptr);
  StartRatePhase(s, start);
  EXPECT_TRUE(s.rate.active);
  ASSERT_NE(s.controller, nullptr);
  const float initial = s.live.lambda_e;
  EXPECT_GT(initial, 0.f);
  ControlRate(s, start + 4);
  EXPECT_EQ(s.live.lambda_e, initial) << "not due";
  ControlRate(s, start + 5);
  EXPECT_GT(s.live.lambda_e, initial);
}

TEST(TrainEvents, QuantAwareStepsSeeTheQuantizedGridsAndGetTheFloatOnesBack) {
  TrainOptions o = TinyRun();
  o.lambda_e = 1e-9f;  // quantization-aware from the rate phase, at 65
  TinySession r(o);
  TrainSession& s = r.s;
  const std::vector<float> floats = s.model->density().params();
  QuantizeGrids(s, s.schedule.qat_start - 1);
  EXPECT_FALSE(s.rate.active);
  EXPECT_EQ(s.model->density().params(), floats);
  QuantizeGrids(s, s.schedule.qat_start);
  EXPECT_TRUE(s.rate.active);  // the steps are frozen for the quantizer
  EXPECT_NE(s.model->density().params(), floats);
  s.qat.Restore(s.model);
  EXPECT_EQ(s.model->density().params(), floats);
}

TEST(TrainEvents, PruningRemovesComponentsWhenDueAndBitsAreDear) {
  TrainOptions o = TinyRun();
  o.lambda_e = 1.0f;  // every bit outweighs what a component of a fresh model renders
  o.prune_at = {0.5f};
  o.density_rank = 4;  // few components, units and rays: each is rendered without it
  o.appearance_rank = 4;
  o.plane_block[0] = 4;
  o.mlp_hidden = 16;
  o.prune_rays = 128;
  o.qat_start = 1.f;  // the test prunes the float grids
  TinySession r(o);
  TrainSession& s = r.s;
  const int due = s.schedule.rate_start + 28 - 1;  // 0.5 of the 55 iterations of the rate phase
  const int components = ComponentCount(*s.model);
  PruneByRate(s, due);
  EXPECT_EQ(ComponentCount(*s.model), components) << "the rate objective is not on yet";
  StartRatePhase(s, s.schedule.rate_start);
  PruneByRate(s, due - 1);
  EXPECT_EQ(ComponentCount(*s.model), components) << "not due";
  PruneByRate(s, due);
  EXPECT_LT(ComponentCount(*s.model), components);
  EXPECT_LT(s.model->head().config().hidden, 16);
  EXPECT_EQ(s.opt.density.size(), s.model->density().params().size());
}

TEST(TrainEvents, CameraRoundsRefineOnlyWhenDue) {
  TrainOptions o = TinyRun();
  o.refine_cameras = Toggle::kOn;  // rounds every 2 steps from 24 to 96
  TinySession r(o);
  TrainSession& s = r.s;
  ASSERT_EQ(s.progress.cameras.size(), 8u);
  RefineCameraRound(s, 22);
  EXPECT_TRUE(s.result.camera_refinement.empty());
  RefineCameraRound(s, 23);
  EXPECT_EQ(s.result.camera_refinement.size(), 1u);
}

TEST(TrainEvents, EvaluationsCheckpointsAndStopsFollowTheStepsDone) {
  const testing_util::ScopedTempDir tmp("ecrf_events");
  TrainOptions o = TinyRun();
  o.out_dir = tmp.path();
  o.eval_every = 2;
  o.checkpoint_every = 2;
  o.stop_after = 3;
  TinySession r(o);
  TrainSession& s = r.s;
  const std::string ckpt = o.out_dir + "/checkpoint.ckpt";
  EvaluateTestCurve(s, 0);
  EXPECT_TRUE(s.result.psnr_curve.empty());
  EvaluateTestCurve(s, 1);
  ASSERT_EQ(s.result.psnr_curve.size(), 1u);
  EXPECT_GT(s.result.psnr_curve[0].second, 0.0);
  EXPECT_GT(s.eval_seconds, 0.0);

  SaveRunCheckpoint(s, 0);
  EXPECT_EQ(std::fopen(ckpt.c_str(), "rb"), nullptr);
  SaveRunCheckpoint(s, 1);
  EXPECT_EQ(ReadCheckpointRunInfo(ckpt).iteration, 2);
  s.model->density().params()[0] = NAN;  // a diverged model is never written
  EXPECT_THROW(SaveRunCheckpoint(s, 3), std::runtime_error);
  EXPECT_EQ(ReadCheckpointRunInfo(ckpt).iteration, 2);

  EXPECT_NO_THROW(StopIfAsked(s, 1));
  EXPECT_THROW(StopIfAsked(s, 2), TrainingStopped);
}

TEST(TrainEvents, AStopByTimeWritesItsOwnCheckpoint) {
  const testing_util::ScopedTempDir tmp("ecrf_events");
  TrainOptions o = TinyRun();
  o.out_dir = tmp.path();
  o.stop_after_minutes = 60.f;
  TinySession not_yet(o);
  EXPECT_NO_THROW(StopIfAsked(not_yet.s, 4));  // an hour has not passed
  EXPECT_FALSE(std::filesystem::exists(o.out_dir + "/checkpoint.ckpt"));
  o.stop_after_minutes = 1e-6f;
  TinySession now(o);
  EXPECT_THROW(StopIfAsked(now.s, 4), TrainingStopped);
  EXPECT_EQ(ReadCheckpointRunInfo(o.out_dir + "/checkpoint.ckpt").iteration, 5);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
