#include "trainer/train/camera_refine.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <vector>

#include "tests/common/camera_angle.h"
#include "trainer/scenes/capture_scene.h"
#include "trainer/train/camera_schedule.h"
#include "trainer/train/evaluate.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace trainer {
namespace {

using testing_camera::AngleDeg;
using testing_camera::RotationOf;

// A short training of the built-in scene: a field with texture to align against, trained once for
// the checks that need one (they run in one test: ctest runs each test in its own process, which
// would train the field again for each).
struct TrainedField {
  TrainOptions options;
  Dataset train;
  TensorfModel model;
  TrainedField()
      : options(Options()),
        train(LoadTrainingViews(options, "train")),
        model(ConfigFor(options, train)) {
    Train(options, train, Dataset(), &model, nullptr);
  }
  static TrainOptions Options() {
    TrainOptions o = PresetOptions("tiny");
    o.procedural_scene = ProceduralScene::kBuiltin;
    o.builtin_size = 48;
    o.builtin_views = 16;
    o.iters = 300;
    o.batch_rays = 1024;
    o.progress_every = 1000;
    o.mlp_hidden = 32;
    // The field of a run that refines its cameras: auto early stop is off there (train_fields.def
    // says what a field trained with it leaves to this test's refinement).
    o.early_stop = 0.f;
    return o;
  }
  static const TrainedField& Get() {
    static const TrainedField field;
    return field;
  }
};

// Views the field itself renders from known cameras are the images; the cameras are then moved
// by about two pixels and the focal length is made 3 % short, as structure from motion leaves
// them. Refinement must bring them back.
void RecoversMovedPosesAndFocalLengthOnViewsTheFieldRendered() {
  const TrainedField& f = TrainedField::Get();
  std::vector<View> views;
  std::vector<Camera> truth, cameras;
  std::mt19937 rng(3);
  std::normal_distribution<double> jitter(0.0, 1.0);
  for (size_t v = 0; v < 8; ++v) {
    const Camera& c = f.train.views[v].camera;
    views.push_back({c, RenderView(f.model, c), f.train.views[v].name});
    truth.push_back(c);
    // About a degree of rotation and a centimetre-scale move of each camera.
    const double omega[3] = {0.012 * jitter(rng), 0.012 * jitter(rng), 0.012 * jitter(rng)};
    const Eigen::Vector3d w(omega[0], omega[1], omega[2]);
    Camera moved = c;
    const Eigen::Matrix3d r =
        RotationOf(c) * Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) moved.c2w[i][j] = r(i, j);
      moved.c2w[i][3] += 0.01 * jitter(rng);
    }
    moved.fx *= 0.97;
    moved.fy *= 0.97;
    cameras.push_back(moved);
  }
  double angle_before = 0, move_before = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    angle_before += AngleDeg(cameras[v], truth[v]) / double(views.size());
    for (int i = 0; i < 3; ++i) move_before += std::abs(cameras[v].c2w[i][3] - truth[v].c2w[i][3]);
  }
  CameraRefineOptions o;
  o.steps = 6;
  o.pixels_per_view = 256;
  const CameraRefineStats s = RefineCameras(f.model, views, nullptr, o, &cameras);
  double angle_after = 0, move_after = 0;
  for (size_t v = 0; v < views.size(); ++v) {
    angle_after += AngleDeg(cameras[v], truth[v]) / double(views.size());
    for (int i = 0; i < 3; ++i) move_after += std::abs(cameras[v].c2w[i][3] - truth[v].c2w[i][3]);
    EXPECT_EQ(cameras[v].fx, cameras[0].fx);  // one shared camera
  }
  const double focal_before = 0.03, focal_after = std::abs(cameras[0].fx / truth[0].fx - 1.0);
  std::printf(
      "pixel error %.3g -> %.3g in %d steps; rotation %.3f -> %.3f deg, centres %.4f -> %.4f, "
      "focal %.4f -> %.4f\n",
      s.mse_before, s.mse_after, s.steps_taken, angle_before, angle_after, move_before, move_after,
      focal_before, focal_after);
  // The centres are printed, not checked: for an object filmed from afar, moving a camera
  // sideways and turning it look alike, and the pixels decide between them only weakly.
  EXPECT_LT(s.mse_after, 0.1 * s.mse_before);
  EXPECT_LT(angle_after, 0.5 * angle_before);
  EXPECT_LT(focal_after, 0.5 * focal_before);
}

// Cameras at their true place stay there: the field renders them exactly.
void LeavesExactCamerasAlone() {
  const TrainedField& f = TrainedField::Get();
  std::vector<View> views;
  std::vector<Camera> cameras;
  for (size_t v = 0; v < 4; ++v) {
    const Camera& c = f.train.views[v].camera;
    views.push_back({c, RenderView(f.model, c), f.train.views[v].name});
    cameras.push_back(c);
  }
  const std::vector<Camera> truth = cameras;
  const CameraRefineStats s =
      RefineCameras(f.model, views, nullptr, CameraRefineOptions(), &cameras);
  EXPECT_EQ(s.mse_before, 0.0);
  EXPECT_EQ(s.steps_taken, 0);  // no step can lower an error of 0
  for (size_t v = 0; v < views.size(); ++v)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j) EXPECT_EQ(cameras[v].c2w[i][j], truth[v].c2w[i][j]);
}

// Only the scored held-out views are aligned photometrically (the others follow the training
// cameras' drift alone, at no rendering cost), and an aligned camera does not depend on which
// other views were aligned with it.
void AlignsOnlyTheScoredHeldOutViews() {
  const TrainedField& f = TrainedField::Get();
  Dataset train, test;
  std::vector<Camera> refined;
  std::mt19937 rng(9);
  std::normal_distribution<double> jitter(0.0, 0.01);
  for (size_t v = 0; v < 4; ++v) {
    const Camera& c = f.train.views[v].camera;
    train.views.push_back({c, Image(), f.train.views[v].name});
    refined.push_back(c);  // the training cameras did not move: nothing to follow
    // Held-out views the field renders exactly, their cameras turned by about half a degree.
    const Camera& h = f.train.views[v + 4].camera;
    Camera turned = h;
    const Eigen::Vector3d w(jitter(rng), jitter(rng), jitter(rng));
    const Eigen::Matrix3d r =
        RotationOf(h) * Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) turned.c2w[i][j] = r(i, j);
    test.views.push_back({turned, RenderView(f.model, h), f.train.views[v + 4].name});
  }
  std::vector<CameraRefineStats> stats;
  const std::vector<Camera> some =
      AlignHeldOutCameras(f.model, train, test, refined, {1, 3}, 7, &stats);
  const std::vector<Camera> all =
      AlignHeldOutCameras(f.model, train, test, refined, {0, 1, 2, 3}, 7, nullptr);
  ASSERT_EQ(stats.size(), 1u);
  EXPECT_LT(stats[0].mse_after, 0.5 * stats[0].mse_before);
  for (const size_t v : {size_t(0), size_t(2)}) {  // not scored: where the drift leaves them
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j)
        EXPECT_NEAR(some[v].c2w[i][j], test.views[v].camera.c2w[i][j], 1e-12);
  }
  for (const size_t v : {size_t(1), size_t(3)}) {
    const Camera& truth = f.train.views[v + 4].camera;
    EXPECT_LT(AngleDeg(some[v], truth), 0.5 * AngleDeg(test.views[v].camera, truth));
    // Each view's pose is solved on its own pixels: aligning the others beside it changes little.
    // Half a view (the half-image protocol) pins a pose less than a whole one: view 3's left half
    // leaves a flat valley where the joint solves stop 0.17 deg apart (whole views: < 0.1 x).
    EXPECT_LT(AngleDeg(some[v], all[v]), 0.2 * AngleDeg(test.views[v].camera, truth));
  }
  EXPECT_THROW(AlignHeldOutCameras(f.model, train, test, refined, {4}, 7, nullptr),
               std::invalid_argument);

  // The half-image protocol: the cameras are fitted on the left halves only, so any right half
  // (what is scored) gives the same cameras, bit for bit.
  Dataset scrambled = test;
  std::uniform_real_distribution<float> noise(0.f, 1.f);
  for (View& v : scrambled.views) {
    for (int y = 0; y < v.rgb.height; ++y)
      for (int x = v.rgb.width / 2; x < v.rgb.width; ++x)
        for (int c = 0; c < v.rgb.channels; ++c) v.rgb.at(x, y, c) = noise(rng);
  }
  const std::vector<Camera> again =
      AlignHeldOutCameras(f.model, train, scrambled, refined, {1, 3}, 7, nullptr);
  for (const size_t v : {size_t(1), size_t(3)})
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 4; ++j) EXPECT_EQ(again[v].c2w[i][j], some[v].c2w[i][j]);
  // And the views that carry those cameras are scored on their right halves only.
  const Dataset aligned = WithCameras(test, some);
  for (const View& v : aligned.views) EXPECT_EQ(v.fitted_columns, v.rgb.width / 2);
  const EvalResult clean = Evaluate(f.model, aligned, 1, 0, false);
  Dataset left_spoilt = aligned;
  for (View& v : left_spoilt.views)
    for (int y = 0; y < v.rgb.height; ++y)
      for (int x = 0; x < v.rgb.width / 2; ++x) v.rgb.at(x, y, 0) = noise(rng);
  const EvalResult spoilt = Evaluate(f.model, left_spoilt, 1, 0, false);
  EXPECT_EQ(spoilt.psnr, clean.psnr);  // the left halves are not scored
  EXPECT_EQ(spoilt.ssim, clean.ssim);
  EXPECT_EQ(clean.fitted_columns, test.views[0].rgb.width / 2);
}

TEST(CameraRefineTest, OnAFieldTrainedOnce) {
  {
    SCOPED_TRACE("moved poses and focal length recovered");
    RecoversMovedPosesAndFocalLengthOnViewsTheFieldRendered();
  }
  {
    SCOPED_TRACE("exact cameras left alone");
    LeavesExactCamerasAlone();
  }
  {
    SCOPED_TRACE("only the scored held-out views aligned");
    AlignsOnlyTheScoredHeldOutViews();
  }
}

// Held-out cameras posed with the training ones follow their common drift exactly, and take the
// refined shared intrinsics at their own image size.
TEST(CameraRefineTest, HeldOutCamerasFollowTheTrainingCamerasDrift) {
  const Dataset capture = MakeCaptureScene("train", 32, 24, 12, 5);
  std::vector<Camera> before, after;
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(0.2, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(0.3, -0.1, 0.2);
  const double scale = 1.1;
  auto drift = [&](Camera c) {
    const Eigen::Matrix3d r = turn * RotationOf(c);
    const Eigen::Vector3d centre =
        scale * turn * Eigen::Vector3d(c.c2w[0][3], c.c2w[1][3], c.c2w[2][3]) + shift;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) c.c2w[i][j] = r(i, j);
      c.c2w[i][3] = centre[i];
    }
    return c;
  };
  for (const View& v : capture.views) {
    before.push_back(v.camera);
    Camera moved = drift(v.camera);
    moved.fx *= 1.02;
    moved.k1 = -0.1;
    after.push_back(moved);
  }
  Camera held_out = before[0];
  held_out.c2w[0][3] += 0.5;  // somewhere else
  Camera half = ScaledCamera(held_out, 2);
  const std::vector<Camera> out = FollowRefinedCameras(before, after, {held_out, half});
  const Camera expected = drift(held_out);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(out[0].c2w[i][j], expected.c2w[i][j], 1e-9);
  EXPECT_DOUBLE_EQ(out[0].fx, before[0].fx * 1.02);
  EXPECT_DOUBLE_EQ(out[0].k1, -0.1);
  EXPECT_EQ(out[1].width, half.width);
  EXPECT_DOUBLE_EQ(out[1].fx, half.fx * 1.02);
  EXPECT_DOUBLE_EQ(out[1].cx, half.cx);
}

TEST(CameraRefineTest, AutoRefinesEstimatedPosesOnly) {
  TrainOptions o;
  Dataset data;
  EXPECT_FALSE(RefineCamerasOn(o, data));  // rendered cameras (Blender layout, procedural scenes)
  data.estimated_poses = true;             // transforms.json of Instant-NGP / nerfstudio, LLFF
  EXPECT_TRUE(RefineCamerasOn(o, data));
  o.refine_cameras = Toggle::kOff;
  EXPECT_FALSE(RefineCamerasOn(o, data));
  o.refine_cameras = Toggle::kOn;
  data.estimated_poses = false;
  EXPECT_TRUE(RefineCamerasOn(o, data));
  EXPECT_THROW(ChoiceFromName<Toggle>("sometimes", "--refine-cameras"), std::invalid_argument);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
