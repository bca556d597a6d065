// The events that record the run rather than train it: the held-out PSNR curve, checkpoints,
// --stop-after, and the work after the last step.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "trainer/data/seconds_since.h"
#include "trainer/train/camera_refine.h"
#include "trainer/train/evaluate.h"
#include "trainer/train/stop_signal.h"
#include "trainer/train/train_events.h"

namespace ecrf {
namespace trainer {

void EvaluateTestCurve(TrainSession& s, int it) {
  if (!s.schedule.EvalDue(it + 1)) return;
  const auto eval_start = TrainClock::now();
  // With refined cameras, the held-out ones are aligned first, as for the final score.
  const bool refined = s.schedule.cameras.on;
  const Dataset scored =
      refined
          ? WithCameras(s.test, AlignHeldOutCameras(*s.model, s.train, s.test, s.progress.cameras,
                                                    s.scored_views, s.o.seed, nullptr))
          : Dataset();
  const EvalResult e =
      Evaluate(*s.model, refined ? scored : s.test, s.scored_stride, s.o.max_test_views, false);
  s.eval_seconds += SecondsSince(eval_start);
  s.result.psnr_curve.emplace_back(s.TrainSeconds() / 60.0, e.psnr);
  std::fprintf(stderr, "%s  test psnr %.2f dB at %.1f min (training time)\n", isatty(2) ? "\n" : "",
               e.psnr, s.result.psnr_curve.back().first);
}

namespace {

bool TimedCheckpointDue(const TrainSession& s, int done) {
  return !s.checkpoint_path.empty() && s.o.checkpoint_minutes > 0.f && done < s.o.iters &&
         SecondsSince(s.last_checkpoint) >= 60.0 * s.o.checkpoint_minutes;
}

void WriteRunCheckpoint(TrainSession& s, int it) {
  CheckModelFinite(*s.model, it, s.checkpoint_path);
  s.SaveCheckpoint(it + 1, s.TrainSeconds());
  s.last_checkpoint = TrainClock::now();
  s.last_checkpoint_done = it + 1;
}

}  // namespace

void SaveRunCheckpoint(TrainSession& s, int it) {
  const int done = it + 1;
  if (s.schedule.CheckpointDue(done) || TimedCheckpointDue(s, done)) WriteRunCheckpoint(s, it);
}

void StopIfAsked(TrainSession& s, int it) {
  const int done = it + 1;
  if (const int signal = StopSignal(); signal != 0 && done < s.o.iters) {
    // This step's checkpoint, unless SaveRunCheckpoint has just written it.
    if (!s.checkpoint_path.empty() && s.last_checkpoint_done != done) WriteRunCheckpoint(s, it);
    throw TrainingStopped(
        std::string("training interrupted (") + StopSignalName(signal) + ") after iteration " +
            std::to_string(done) + " of " + std::to_string(s.o.iters) +
            (s.checkpoint_path.empty() ? std::string(": no output directory, nothing kept")
                                       : "; " + s.checkpoint_path + " holds it"),
        signal);
  }
  if (s.schedule.StopDue(done)) {
    throw TrainingStopped("training stopped after iteration " + std::to_string(done) +
                          " (--stop-after)");
  }
  const double minutes = SecondsSince(s.started) / 60.0;
  if (s.o.stop_after_minutes > 0.f && minutes >= s.o.stop_after_minutes && done < s.o.iters) {
    // Unlike --stop-after, the stop is not known in advance: its checkpoint is written here.
    if (!s.checkpoint_path.empty() && s.last_checkpoint_done != done) WriteRunCheckpoint(s, it);
    throw TrainingStopped("training stopped after " + std::to_string(int(minutes)) +
                          " minutes at iteration " + std::to_string(done) +
                          " (--stop-after-minutes; --resume continues it)");
  }
}

namespace {

void ReportExposureCodes(TrainSession& s) {
  const std::vector<float>& g = s.progress.exposure.log_gain();
  const auto [lo, hi] = std::minmax_element(g.begin(), g.end());
  std::fprintf(stderr,
               "exposure codes: the %d training images' gains span %.3f-%.3f of the neutral "
               "exposure the file renders\n",
               s.progress.exposure.views(), std::exp(*lo), std::exp(*hi));
  s.result.exposure_log_gain = g;
}

}  // namespace

TrainResult FinishTraining(TrainSession& s) {
  const TrainOptions& o = s.o;
  TensorfModel* model = s.model;
  TrainResult& result = s.result;
  if (isatty(2)) std::fprintf(stderr, "\n");
  if (s.exposure_on) ReportExposureCodes(s);
  // Before the held-out cameras are aligned to the field: the file's field has this mask.
  RefreshAlphaMask(s);
  if (s.schedule.cameras.on) {
    result.train_cameras = s.progress.cameras;
    result.test_cameras = AlignHeldOutCameras(*model, s.train, s.test, s.progress.cameras,
                                              s.scored_views, o.seed, &result.camera_refinement);
  }
  result.iterations = o.iters;
  result.final_lambda_e = s.live.lambda_e;
  result.train_seconds = s.TrainSeconds();
  CheckModelFinite(*model, o.iters - 1, s.checkpoint_path);
  if (!s.checkpoint_path.empty()) {
    try {
      s.SaveCheckpoint(o.iters, result.train_seconds);
    } catch (const std::runtime_error& e) {
      // A full disk (or a file size limit): the checkpoint is far larger than the scene file the
      // run is for, and the model is in memory. Say so and go on to write the file.
      std::fprintf(stderr,
                   "warning: %s\nwarning: the final checkpoint was not written (ecrf encode RUN "
                   "needs it); writing the run's file from the model in memory\n",
                   e.what());
    }
  }
  if (o.report_rate && (!s.schedule.use_rate || !s.rate.active)) {
    // Without the rate objective (or a run too short to reach its phase: --iters 1), fit an
    // entropy model to the final grids anyway so every run reports the size its coefficients
    // would cost (the lambda_e = 0 point of a sweep).
    if (!s.rate.active) s.rate.Activate(*model, o);
    TrainOptions fit = o;
    fit.lambda_e = 0.0f;
    for (int k = 0; k < 300; ++k) s.rate.Step(*model, fit, s.progress.rng());
  }
  if (s.rate.active || o.report_rate) result.rate = s.rate.Evaluate(*model);

  // The float model is scored on request only: the decoded file is what a user gets (and is
  // always scored by the caller); scoring both doubled the evaluation time of a default run.
  if (o.score_float) {
    result.test = Evaluate(*model, WithCameras(s.test, result.test_cameras), s.scored_stride,
                           o.max_test_views, o.save_renders);
    if (o.eval_every > 0)
      result.psnr_curve.emplace_back(result.train_seconds / 60.0, result.test.psnr);
  }
  return std::move(result);
}

}  // namespace trainer
}  // namespace ecrf
