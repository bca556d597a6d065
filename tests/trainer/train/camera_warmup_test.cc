#include "trainer/train/camera_warmup.h"
#include "tests/common/scoped_temp_dir.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "tests/common/camera_angle.h"
#include "trainer/data/scene_fit.h"
#include "trainer/train/camera_schedule.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace trainer {
namespace {

using testing_camera::AngleDeg;
using testing_camera::RotationOf;

double MeanAngleDeg(const Dataset& data, const std::vector<Camera>& truth) {
  double sum = 0.0;
  for (size_t v = 0; v < truth.size(); ++v) sum += AngleDeg(data.views[v].camera, truth[v]);
  return sum / double(truth.size());
}

bool SameCameras(const Dataset& a, const Dataset& b) {
  if (a.views.size() != b.views.size()) return false;
  for (size_t v = 0; v < a.views.size(); ++v) {
    const Camera &x = a.views[v].camera, &y = b.views[v].camera;
    if (std::memcmp(x.c2w, y.c2w, sizeof(x.c2w)) != 0 || x.fx != y.fx || x.fy != y.fy ||
        x.cx != y.cx || x.cy != y.cy || x.k1 != y.k1 || x.p1 != y.p1 || x.p2 != y.p2)
      return false;
  }
  return true;
}

TEST(CameraWarmupTest, RunsOnlyWhenTheCamerasAreRefined) {
  TrainOptions o = PresetOptions("tiny");
  o.iters = 1500;
  Dataset data;
  EXPECT_EQ(CameraWarmupIterations(o, data), 0);  // exact (rendered) cameras are not refined
  data.estimated_poses = true;
  EXPECT_EQ(CameraWarmupIterations(o, data), 750);  // auto: half the run
  o.camera_warmup_iters = 300;
  EXPECT_EQ(CameraWarmupIterations(o, data), 300);
  o.camera_warmup_iters = 0;
  EXPECT_EQ(CameraWarmupIterations(o, data), 0);
  o.camera_warmup_iters = -1;
  o.refine_cameras = Toggle::kOff;
  EXPECT_EQ(CameraWarmupIterations(o, data), 0);
  o.refine_cameras = Toggle::kOn;
  data.estimated_poses = false;
  EXPECT_EQ(CameraWarmupIterations(o, data), 750);
  o.out_dir = "run";
  EXPECT_EQ(CameraWarmupDir(o), "run/warmup");
  Dataset train = data, test = data;
  o.camera_warmup_iters = 0;
  EXPECT_FALSE(WarmUpCameras(o, SceneFit(), &train, &test));  // nothing due: nothing trained

  // A run an older ecrf started (a checkpoint, no warm-up beside it) resumes without one: its
  // field was trained on the dataset's cameras.
  const testing_util::ScopedTempDir tmp("ecrf_warmup_old");
  o.out_dir = tmp.path();
  o.camera_warmup_iters = -1;
  o.resume = true;
  std::fclose(std::fopen((o.out_dir + "/checkpoint.ckpt").c_str(), "wb"));
  EXPECT_FALSE(WarmUpCameras(o, SceneFit(), &train, &test));
  EXPECT_FALSE(train.warmed_up_cameras);
}

// The warm-up trains without what only the file needs, and refines as often in iterations as the
// run: every 30 iterations for a 1,500-iteration run (16 rounds in its 750), not every 15.
TEST(CameraWarmupTest, TrainsForTheCamerasAndRefinesAsOftenAsTheRun) {
  TrainOptions o = PresetOptions("tiny");
  o.iters = 1500;
  o.out_dir = "run";
  o.prune_at = {0.5f};
  o.eval_every = 100;
  o.resume = true;
  Dataset data;
  data.estimated_poses = true;
  const TrainOptions w = CameraWarmupOptions(o, CameraWarmupIterations(o, data));
  EXPECT_EQ(w.iters, 750);
  EXPECT_EQ(w.lambda_e, 0.0f);
  EXPECT_TRUE(w.prune_at.empty());
  EXPECT_EQ(w.eval_every, 0);
  EXPECT_TRUE(o.report_rate);
  EXPECT_FALSE(w.report_rate);  // no entropy fit for a size nobody reads
  EXPECT_EQ(w.camera_warmup_iters, 0);
  EXPECT_FALSE(w.resume);
  EXPECT_EQ(w.out_dir, "run/warmup");
  const CameraRefineSchedule s = CameraRefineScheduleFor(w, data);
  EXPECT_EQ(s.every, 30);
  int rounds = 0;
  for (int done = 1; done <= w.iters; ++done) rounds += s.Due(done) ? 1 : 0;
  EXPECT_EQ(rounds, 16);
  o.refine_cameras_every = 7;  // an explicit cadence is kept
  EXPECT_EQ(CameraWarmupOptions(o, 750).refine_cameras_every, 7);
}

// The built-in scene's training cameras turned by about a degree, as structure from motion leaves
// them: the warm-up brings them back part of the way (as far as a short, coarse field lets it), and
// a finished warm-up resumed gives the same cameras bit for bit (the run trains from them, so its
// resume depends on it).
TEST(CameraWarmupTest, TurnedCamerasComeBackAndAFinishedWarmUpReloadsBitForBit) {
  TrainOptions o = PresetOptions("tiny");
  o.procedural_scene = ProceduralScene::kBuiltin;
  o.builtin_size = 48;
  o.builtin_views = 16;
  o.iters = 400;
  o.camera_warmup_iters = 200;
  o.refine_cameras = Toggle::kOn;
  o.refine_cameras_every = 15;
  o.batch_rays = 1024;
  o.progress_every = 1000;
  o.mlp_hidden = 32;
  const testing_util::ScopedTempDir tmp("ecrf_warmup");
  o.out_dir = tmp.path();

  Dataset train = LoadTrainingViews(o, "train");
  Dataset test = LoadTrainingViews(o, "test");
  std::vector<Camera> truth;
  std::mt19937 rng(5);
  std::normal_distribution<double> jitter(0.0, 0.012);
  for (View& v : train.views) {
    truth.push_back(v.camera);
    const Eigen::Vector3d w(jitter(rng), jitter(rng), jitter(rng));
    const Eigen::Matrix3d r =
        RotationOf(v.camera) * Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) v.camera.c2w[i][j] = r(i, j);
  }
  const double before = MeanAngleDeg(train, truth);
  const SceneFit fit = FitScene(o.scene_type, train);

  Dataset a_train = train, a_test = test;
  ASSERT_TRUE(WarmUpCameras(o, fit, &a_train, &a_test));
  const double after = MeanAngleDeg(a_train, truth);
  std::printf("mean rotation error %.3f -> %.3f deg\n", before, after);
  EXPECT_LT(after, 0.8 * before);
  EXPECT_EQ(access((o.out_dir + "/warmup/checkpoint.ckpt").c_str(), R_OK), 0);
  EXPECT_FALSE(SameCameras(a_test, test));  // the held-out cameras were aligned too
  EXPECT_TRUE(a_train.warmed_up_cameras);
  EXPECT_EQ(CameraRefineScheduleFor(o, a_train).from, 200);  // the run refines from half-way
  EXPECT_EQ(CameraRefineScheduleFor(o, train).from, 80);

  TrainOptions resumed = o;
  resumed.resume = true;
  Dataset b_train = train, b_test = test;
  ASSERT_TRUE(WarmUpCameras(resumed, fit, &b_train, &b_test));
  EXPECT_TRUE(SameCameras(a_train, b_train));
  EXPECT_TRUE(SameCameras(a_test, b_test));
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
