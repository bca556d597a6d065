#include "trainer/train/camera_warmup.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "trainer/train/camera_refine.h"
#include "trainer/train/camera_schedule.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace trainer {

int CameraWarmupIterations(const TrainOptions& o, const Dataset& train) {
  if (o.camera_warmup_iters == 0 || !RefineCamerasOn(o, train)) return 0;
  return o.camera_warmup_iters > 0 ? o.camera_warmup_iters : std::max(1, o.iters / 2);
}

std::string CameraWarmupDir(const TrainOptions& o) {
  return o.out_dir.empty() ? std::string() : o.out_dir + "/warmup";
}

TrainOptions CameraWarmupOptions(const TrainOptions& o, int iters) {
  TrainOptions w = o;
  w.iters = iters;
  w.camera_warmup_iters = 0;
  // Refinement rounds as far apart in iterations as the run's own (auto: iters / 50 of the run,
  // not of the shorter warm-up): each round costs about as much as 30 training iterations, and
  // half as many rounds took the prepared capture from 25.66 to 25.93 dB held-out in 6.1 instead
  // of 8.1 min (docs/photos-to-dataset.md).
  if (w.refine_cameras_every <= 0) w.refine_cameras_every = std::max(1, o.iters / 50);
  // Only the cameras are kept: no rate objective or size report, quantization, pruning or
  // scoring.
  w.lambda_e = 0.0f;
  w.target_bytes = 0;
  w.qat_start = 1.0f;
  w.prune_at.clear();
  w.eval_every = 0;
  w.score_float = false;
  w.report_rate = false;
  w.save_renders = false;
  w.stop_after = 0;
  w.out_dir = CameraWarmupDir(o);
  w.resume = false;
  return w;
}

bool WarmUpCameras(const TrainOptions& o, const SceneFit& fit, Dataset* train, Dataset* test) {
  const int iters = CameraWarmupIterations(o, *train);
  if (iters == 0) return false;
  TrainOptions w = CameraWarmupOptions(o, iters);
  std::error_code error;
  w.resume = o.resume && !w.out_dir.empty() &&
             std::filesystem::exists(w.out_dir + "/checkpoint.ckpt", error);
  if (o.resume && !w.resume && std::filesystem::exists(o.out_dir + "/checkpoint.ckpt", error)) {
    // The run's field was trained without a warm-up (an older ecrf started it): its cameras are
    // the dataset's.
    std::fprintf(stderr, "camera warm-up: none in the resumed run (%s has no checkpoint)\n",
                 w.out_dir.c_str());
    return false;
  }
  if (!w.out_dir.empty()) std::filesystem::create_directories(w.out_dir);
  std::fprintf(stderr,
               "camera warm-up: %d iterations on the estimated cameras, refining them (%s); the "
               "run's field then trains afresh from the refined cameras\n",
               iters, w.out_dir.empty() ? "no checkpoint" : (w.out_dir + "/").c_str());
  TensorfModel model(ConfigFor(w, *train, fit));
  const TrainResult r = Train(w, *train, *test, &model, nullptr);
  std::fprintf(stderr,
               "camera warm-up done: the run starts from its %zu refined training cameras and %zu "
               "held-out ones carried with them (the scored ones aligned)\n",
               r.train_cameras.size(), r.test_cameras.size());
  *train = WithCameras(std::move(*train), r.train_cameras);
  *test = WithCameras(std::move(*test), r.test_cameras);
  train->warmed_up_cameras = true;
  return true;
}

}  // namespace trainer
}  // namespace ecrf
