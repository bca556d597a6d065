#include "trainer/train/train_session.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "trainer/data/seconds_since.h"
#include "trainer/train/eval_progress.h"

namespace ecrf {
namespace trainer {

std::array<int, 3> ResolutionFor(long voxels, const Aabb& box) {
  double lo[3], hi[3];
  int res[3];
  for (int a = 0; a < 3; ++a) lo[a] = box.min[a], hi[a] = box.max[a];
  ResolutionForVoxels(voxels, lo, hi, res);
  return {res[0], res[1], res[2]};
}

namespace {

std::string CheckpointPathFor(const TrainOptions& o) {
  return o.out_dir.empty() ? std::string() : o.out_dir + "/checkpoint.ckpt";
}

bool ExposureCodesOn(const TrainOptions& o, const TensorfModel& model) {
  return IsOn(o.exposure_codes, model.unbounded() || model.forward());
}

// Only the rays that meet the box train (TensoRF's filtering_rays with bbox_only). Every ray of
// an unbounded scene meets its cube, and a forward-facing scene's box is in NDC.
void KeepRaysThroughTheBox(const TensorfModel& model, RaySet* rays) {
  if (model.unbounded() || model.forward()) return;
  const Aabb box = model.aabb();
  rays->Filter([&box](const float* org, const float* dir) {
    float tn, tf;
    RayAabb(box, org, dir, &tn, &tf);
    return tf > tn;
  });
}

// A checkpoint from before ecrf saved the training state: continue approximately (fresh
// optimizer moments and generator, the schedule position recomputed).
void ResumeApproximately(TrainSession& s) {
  const TrainOptions& o = s.o;
  std::fprintf(stderr,
               "warning: %s has no training state (an older ecrf wrote it): the resumed run "
               "will not equal an uninterrupted one\n",
               s.checkpoint_path.c_str());
  for (int m : s.schedule.mask_at) {
    if (s.first_iter > m) s.progress.l1_weight = o.l1_weight_rest;
  }
  int last_reset = 0;
  for (int m : s.schedule.upsample_at) {
    if (m < s.first_iter) last_reset = m;
  }
  s.opt.lr_scale = std::pow(s.lr_factor, float(s.first_iter - last_reset));
  s.progress.rng.seed(o.seed + uint64_t(s.first_iter));
}

}  // namespace

ModelStart StartModel(const TrainOptions& o, const Dataset& train, TensorfModel* model,
                      RateState* rate) {
  rate->Configure(o);
  if (train.views.empty()) throw std::invalid_argument("the training split has no views");
  ModelStart start;
  start.started = TrainClock::now();
  const std::string ckpt_path = CheckpointPathFor(o);
  if (o.resume && (ckpt_path.empty() || access(ckpt_path.c_str(), R_OK) != 0)) {
    throw std::runtime_error(
        "resume: no checkpoint to resume from" +
        (ckpt_path.empty() ? std::string(" (no output directory)") : " at " + ckpt_path));
  }
  if (!o.resume) {
    model->Initialize(ResolutionFor(o.voxels_init, model->config().aabb), o.seed);
    return start;
  }
  start.first_iter = LoadModelCheckpoint(ckpt_path, model, rate, &start.checkpoint);
  // Rate control continues from the lambda_e it had reached.
  if (o.target_bytes > 0 && rate->active && rate->checkpoint_lambda_e > 0.f)
    start.resumed_lambda_e = rate->checkpoint_lambda_e;
  std::fprintf(stderr, "resumed from %s at iteration %d\n", ckpt_path.c_str(), start.first_iter);
  return start;
}

TrainSession::TrainSession(const TrainOptions& options, const Dataset& train_views,
                           const Dataset& test_views, TensorfModel* trained, RateState* rate_state,
                           ModelStart start)
    : o(options),
      train(train_views),
      test(test_views),
      model(trained),
      rate(*rate_state),
      live(options),
      first_iter(start.first_iter),
      started(start.started),
      checkpoint_path(CheckpointPathFor(options)),
      rays(train_views.views) {
  if (start.resumed_lambda_e > 0.f) {
    live.lambda_e = start.resumed_lambda_e;
    controller = std::make_unique<LambdaController>(o.target_bytes, live.lambda_e,
                                                    rate.rate_control_last_bytes);
  }
  opt.Reset(*model);
  exposure_on = ExposureCodesOn(o, *model);
  progress.exposure.Reset(exposure_on ? static_cast<int>(train.views.size()) : 0);
  schedule = ScheduleFor(o, train);
  scored_stride = ScoredTestViewStride(o, test.views.size());
  scored_views = EvalViews(test.views.size(), scored_stride, o.max_test_views);
  if (schedule.cameras.on) {
    for (const View& v : train.views) progress.cameras.push_back(v.camera);
    rays.UseCameras(&progress.cameras);
  }
  tv_density = TvWeightFor(o.tv_weight_density, model->config().scene_model);
  tv_app = TvWeightFor(o.tv_weight_app, model->config().scene_model);
  progress.rng.seed(o.seed);
  progress.l1_weight = o.l1_weight_initial;
  lr_factor = std::pow(o.lr_decay_ratio, 1.0f / float(o.iters));
  const bool exact_resume =
      o.resume && LoadTrainState(start.checkpoint, checkpoint_path, &opt, &rate, &rays, &progress);
  start.checkpoint = Checkpoint();  // the arrays are in the model and the optimizers now
  if (!exact_resume) KeepRaysThroughTheBox(*model, &rays);
  if (o.resume && !exact_resume) ResumeApproximately(*this);
  result.psnr_curve = progress.psnr_curve;
  const size_t n = size_t(o.batch_rays);
  origins.resize(n * 3);
  dirs.resize(n * 3);
  rgb.resize(n * 3);
  ray_views.resize(exposure_on ? n : 0);
  ray_gain.resize(ray_views.size() * 3);
  dl_dgain.resize(ray_gain.size());
  interval_start = TrainClock::now();
}

double TrainSession::TrainSeconds() const {
  return progress.train_seconds + SecondsSince(started) - eval_seconds;
}

void TrainSession::SaveCheckpoint(int done, double train_seconds) {
  TrainProgress now = progress;
  now.train_seconds = train_seconds;
  now.psnr_curve = result.psnr_curve;
  const Checkpoint state = SaveTrainState(opt, rate, rays, now);
  SaveModelCheckpoint(checkpoint_path, *model, done, live, &rate, &state, &o);
}

bool AllFinite(const std::vector<float>& v) {
  // Summing is vectorised and branch-free; any NaN or infinity makes the sum non-finite (a
  // finite overflow to infinity is a divergence too).
  float sum = 0.0f;
  for (float x : v) sum += x * 0.0f;
  return sum == 0.0f;
}

void FailDiverged(int iteration, const std::string& what, const std::string& ckpt_path) {
  std::string keep = ckpt_path.empty() ? std::string("no checkpoint was asked for")
                                       : (access(ckpt_path.c_str(), R_OK) == 0
                                              ? "the last good checkpoint stays in " + ckpt_path
                                              : "no checkpoint had been written yet");
  throw std::runtime_error("training diverged at iteration " + std::to_string(iteration) + ": " +
                           what +
                           " (non-finite input pixels or poses, or a learning rate too high); " +
                           keep + " and nothing else was written");
}

void CheckModelFinite(const TensorfModel& model, int iteration, const std::string& ckpt_path) {
  if (!AllFinite(model.density().params()))
    FailDiverged(iteration, "a density parameter is not finite", ckpt_path);
  if (!AllFinite(model.appearance().params())) {
    FailDiverged(iteration, "an appearance parameter is not finite", ckpt_path);
  }
  if (!AllFinite(model.head().params()))
    FailDiverged(iteration, "an MLP parameter is not finite", ckpt_path);
}

}  // namespace trainer
}  // namespace ecrf
