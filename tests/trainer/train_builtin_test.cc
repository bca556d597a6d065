// End to end: the built-in scene trains to a held-out PSNR that an untrained or broken model
// cannot reach, and checkpoints restore a model that renders identically.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "trainer/trainer.h"

namespace ecrf {
namespace trainer {
namespace {

TrainOptions SmallRun() {
  TrainOptions o = PresetOptions("tiny");
  o.builtin_scene = true;
  o.builtin_size = 48;
  o.builtin_views = 40;
  o.iters = 400;
  o.batch_rays = 1024;
  o.progress_every = 100;
  return o;
}

TEST(TrainBuiltin, ReachesHeldOutPsnrAndCheckpointsRestore) {
  const TrainOptions o = SmallRun();
  const Dataset train = LoadTrainingViews(o, "train");
  const Dataset test = LoadTrainingViews(o, "test");
  ASSERT_FALSE(test.views.empty());

  TensorfModel untrained(ConfigFor(o, train));
  untrained.Initialize({32, 32, 32}, o.seed);
  const double untrained_psnr = Evaluate(untrained, test, 1, 0, false).psnr;

  TensorfModel model(ConfigFor(o, train));
  const TrainResult r = Train(o, train, test, &model);
  std::printf("  untrained %.2f dB, trained %.2f dB (SSIM %.4f) in %.1f s\n", untrained_psnr,
              r.test.psnr, r.test.ssim, r.train_seconds);
  // Thresholds from measurements (see README "Tests"): an untrained field renders almost white
  // (~11 dB against these views); 400 iterations reach ~25 dB.
  EXPECT_GT(r.test.psnr, 22.0);
  EXPECT_GT(r.test.psnr, untrained_psnr + 8.0);
  EXPECT_GT(r.test.ssim, 0.85);

  const std::string path = std::string(::testing::TempDir()) + "/builtin.ckpt";
  SaveModelCheckpoint(path, model, o.iters, o);
  TensorfModel restored(ConfigFor(o, train));
  EXPECT_EQ(LoadModelCheckpoint(path, &restored), o.iters);
  const Image a = RenderView(model, test.views[0].camera);
  const Image b = RenderView(restored, test.views[0].camera);
  ASSERT_EQ(a.pixels.size(), b.pixels.size());
  for (size_t i = 0; i < a.pixels.size(); ++i) ASSERT_EQ(a.pixels[i], b.pixels[i]) << i;
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
