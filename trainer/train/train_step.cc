// The step of the training loop on one batch, and the progress line it feeds.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "trainer/data/seconds_since.h"
#include "trainer/model/volume_render.h"
#include "trainer/train/train_events.h"

namespace ecrf {
namespace trainer {
namespace {

std::string FormatDuration(double seconds) {
  char buf[32];
  const int s = int(seconds + 0.5);
  if (s >= 3600) {
    std::snprintf(buf, sizeof(buf), "%dh%02dm", s / 3600, (s / 60) % 60);
  } else {
    std::snprintf(buf, sizeof(buf), "%dm%02ds", s / 60, s % 60);
  }
  return buf;
}

void PrintProgress(int it, int iters, double loss, double psnr, const TensorfModel& model,
                   const TrainStepStats& stats, double sec_per_it, double elapsed, double est_mb) {
  const int width = 24;
  const int filled = int(double(it) / iters * width);
  char bar[width + 1];
  for (int i = 0; i < width; ++i) bar[i] = i < filled ? '#' : '.';
  bar[width] = 0;
  const auto& r = model.res();
  char size[32] = "";
  if (est_mb >= 0) std::snprintf(size, sizeof(size), " size~%.3fMB", est_mb);
  std::fprintf(stderr,
               "%s[%s] %6d/%d loss %.5f psnr %5.2f%s grid %dx%dx%d samples %.2fM/%.2fM %.2f s/it "
               "elapsed %s eta %s%s",
               isatty(2) ? "\r" : "", bar, it, iters, loss, psnr, size, r[0], r[1], r[2],
               stats.density_samples / 1e6, stats.appearance_samples / 1e6, sec_per_it,
               FormatDuration(elapsed).c_str(), FormatDuration(sec_per_it * (iters - it)).c_str(),
               isatty(2) ? "   " : "\n");
  std::fflush(stderr);
}

}  // namespace

void DrawBatch(TrainSession& s) {
  const int n = s.o.batch_rays;
  s.rays.NextBatch(n, s.progress.rng, s.origins.data(), s.dirs.data(), s.rgb.data(),
                   s.exposure_on ? s.ray_views.data() : nullptr);
  if (s.exposure_on) s.progress.exposure.Gains(n, s.ray_views.data(), s.ray_gain.data());
  s.model->ZeroGrads();
}

void OptimizeStep(TrainSession& s, int it) {
  const TrainOptions& o = s.o;
  TensorfModel* model = s.model;
  const int n = o.batch_rays;
  s.stats = TrainStep(*model, n, s.origins.data(), s.dirs.data(), s.rgb.data(), s.progress.rng(),
                      o.distortion_weight, s.exposure_on ? s.ray_gain.data() : nullptr,
                      s.exposure_on ? s.dl_dgain.data() : nullptr);
  s.qat.Restore(model);  // the gradients of Q(G) go to G unchanged (straight-through)
  // Stop before a NaN is applied. The head's gradient is small and sees every ray.
  if (!std::isfinite(s.stats.mse)) FailDiverged(it, "the loss is not finite", s.checkpoint_path);
  if (!AllFinite(model->head().grads()))
    FailDiverged(it, "a gradient of the appearance MLP is not finite", s.checkpoint_path);
  const float l1_weight = s.progress.l1_weight;
  if (l1_weight > 0) model->DensityL1(l1_weight);
  if (s.tv_density > 0 || s.tv_app > 0) {
    const float decay = std::pow(o.lr_decay_ratio, float(it) / float(o.iters));
    if (s.tv_density > 0) model->density().PlaneTotalVariation(s.tv_density * decay);
    if (s.tv_app > 0) model->appearance().PlaneTotalVariation(s.tv_app * decay);
  }
  if (s.rate.active && s.schedule.use_rate) s.rate.Step(*model, s.live, s.progress.rng());
  s.opt.Step(*model, o);
  if (s.exposure_on) {
    s.progress.exposure.Step(n, s.ray_views.data(), s.ray_gain.data(), s.dl_dgain.data(),
                             o.lr_exposure * s.opt.lr_scale);
  }
  s.opt.lr_scale *= s.lr_factor;
  s.mse_sum += s.stats.mse;
  ++s.mse_count;
}

void ReportProgress(TrainSession& s, int it) {
  const int done = it + 1;
  if (!s.schedule.ProgressDue(done)) return;
  const double mse = s.mse_sum / std::max(1, s.mse_count);
  s.result.final_train_psnr = -10.0 * std::log10(std::max(mse, 1e-12));
  const double spi = SecondsSince(s.interval_start) / std::max(1, s.mse_count);
  PrintProgress(done, s.o.iters, mse, s.result.final_train_psnr, *s.model, s.stats, spi,
                s.TrainSeconds(), s.rate.active ? s.rate.last_bits / 8e6 : -1.0);
  s.mse_sum = 0.0;
  s.mse_count = 0;
  s.interval_start = TrainClock::now();
}

}  // namespace trainer
}  // namespace ecrf
