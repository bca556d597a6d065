#include "trainer/train/trainer.h"

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>
#include <vector>

#include "decoder/contraction.h"
#include "trainer/data/camera.h"
#include "trainer/data/image_metrics.h"
#include "trainer/data/ray_set.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/quant_aware.h"
#include "trainer/rate/train_rate_control.h"
#include "trainer/scenes/builtin_scene.h"
#include "trainer/scenes/capture_scene.h"
#include "trainer/scenes/forward_scene.h"
#include "trainer/scenes/sparse_capture.h"
#include "trainer/train/adam.h"
#include "trainer/train/camera_schedule.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/component_prune.h"
#include "trainer/train/eval_progress.h"
#include "trainer/train/exposure_codes.h"
#include "trainer/train/train_state.h"

namespace ecrf {
namespace trainer {
namespace {

using Clock = std::chrono::steady_clock;

std::array<int, 3> ResolutionFor(long voxels, const Aabb& box) {
  double lo[3], hi[3];
  int res[3];
  for (int a = 0; a < 3; ++a) lo[a] = box.min[a], hi[a] = box.max[a];
  ResolutionForVoxels(voxels, lo, hi, res);
  return {res[0], res[1], res[2]};
}

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

Dataset LoadTrainingViews(const TrainOptions& o, const std::string& split) {
  switch (o.procedural_scene) {
    case ProceduralScene::kCapture:
      return MakeCaptureScene(split, o.capture_width, o.capture_height, o.capture_frames, o.seed);
    case ProceduralScene::kCaptureSparse:
      return MakeSparseCaptureScene(split, o.capture_width, o.capture_height, o.seed);
    case ProceduralScene::kForward:
      return MakeForwardScene(split, o.capture_width, o.capture_height, o.capture_frames, o.seed);
    case ProceduralScene::kBuiltin: {
      const int views = split == "train" ? o.builtin_views : std::max(4, o.builtin_views / 4);
      return MakeBuiltinScene(split, o.builtin_size, o.builtin_size, views, o.seed);
    }
    case ProceduralScene::kNone:
      break;
  }
  if (o.data_dir.empty())
    throw std::invalid_argument("no data: give --data DIR or --scene builtin");
  return LoadDataset(o.data_dir, split, o.downscale);
}

TensorfConfig ConfigFor(const TrainOptions& o, const Dataset& data) {
  return ConfigFor(o, data, FitScene(o.scene_type, data));
}

TensorfConfig ConfigFor(const TrainOptions& o, const Dataset& data, const SceneFit& fit) {
  TensorfConfig c;
  c.density_ranks = {o.density_rank, o.density_rank, o.density_rank};
  c.app_ranks = {o.appearance_rank, o.appearance_rank, o.appearance_rank};
  c.head.num_products = 3 * o.appearance_rank;
  c.head.hidden = o.mlp_hidden;
  c.near = float(data.near);
  c.far = float(data.far);
  c.white_background = data.white_background;
  c.max_samples = o.max_samples_per_ray;
  for (int a = 0; a < 3; ++a) {
    c.aabb.min[a] = float(data.scene_aabb[0][a]);
    c.aabb.max[a] = float(data.scene_aabb[1][a]);
  }
  c.scene_model = fit.model;
  if (fit.model == SceneModel::kForward) {
    c.ndc = fit.ndc;
    c.aabb = fit.roi;  // the NDC box
    c.near = 0.f;      // rays start on the near plane (NDC z = -1)
    c.far = 10.f;  // past the far side of any NDC box of cameras narrower than about 160 degrees
  }
  if (o.weight_threshold >= 0.f) {
    c.weight_threshold = o.weight_threshold;
  } else if (fit.model == SceneModel::kUnbounded) {
    c.weight_threshold = kUnboundedWeightThreshold;
  }
  if (fit.model == SceneModel::kUnbounded) {
    c.roi = fit.roi;
    for (int a = 0; a < 3; ++a) {
      c.aabb.min[a] = -kContractedExtent;
      c.aabb.max[a] = kContractedExtent;
    }
  }
  return c;
}

namespace {

bool AllFinite(const std::vector<float>& v) {
  // Summing is vectorised and branch-free; any NaN or infinity makes the sum non-finite (a
  // finite overflow to infinity is a divergence too).
  float sum = 0.0f;
  for (float x : v) sum += x * 0.0f;
  return sum == 0.0f;
}

[[noreturn]] void FailDiverged(int iteration, const std::string& what,
                               const std::string& ckpt_path) {
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

}  // namespace

int QatStartIteration(const TrainOptions& o) {
  if (o.qat_start < 0.0f) {
    return o.lambda_e > 0.0f || o.target_bytes > 0 ? std::min(RateStartIteration(o), o.iters)
                                                   : o.iters;
  }
  if (!(o.qat_start < 1.0f)) return o.iters;
  int start = int(std::lround(double(std::max(0.0f, o.qat_start)) * o.iters));
  // The steps freeze when quantization-aware training starts, so it waits for the final grid
  // shape and the rate phase (whose steps it shares).
  start = std::max(start, RateStartIteration(o));
  return std::min(start, o.iters);
}

int RateStartIteration(const TrainOptions& o) {
  int start = int(std::lround(double(o.rate_start) * o.iters));
  for (int m : o.upsample_iters)
    start = std::max(start, ScaleMilestone(m, o.iters, o.reference_iters) + 1);
  for (int m : o.alpha_mask_iters)
    start = std::max(start, ScaleMilestone(m, o.iters, o.reference_iters) + 1);
  return start;
}

EncodeOptions RunEncodeOptions(const TrainOptions& o, const RateState& rate) {
  EncodeOptions eo;
  eo.blocks = rate.config;
  eo.steps = rate.steps;
  eo.coef_bits = o.coef_bits;
  eo.mlp_max_level = o.mlp_levels;
  eo.rounding_offset = o.rounding_offset;
  eo.rdoq_lambda = o.rdoq_lambda;
  return eo;
}

namespace {

// Whether a pruning test follows iteration `done`: the shares of --prune-at count from the start
// of the rate phase (the bits of a component are only weighed there) to the end of the run.
bool PruneIteration(const TrainOptions& o, int rate_start, int done) {
  for (float share : o.prune_at) {
    const int at = rate_start + static_cast<int>(std::lround(share * (o.iters - rate_start)));
    if (done == at && done > rate_start && done < o.iters) return true;
  }
  return false;
}

// One pruning test (trainer/train/component_prune.h) on rays drawn without moving the sampler,
// of the model as training renders it (the quantized grids under QAT, each ray at its image's
// exposure gain when the exposure codes are on).
void PruneAt(int done, float lambda_e, const TrainOptions& o, const RaySet& rays,
             const ExposureCodes& exposure, QuantAwareModel* qat, TensorfModel* model,
             Optimizers* opt, const RateState& rate) {
  const auto start = Clock::now();
  const int n = std::max(1, o.prune_rays);
  std::vector<float> origins(size_t(n) * 3), dirs(size_t(n) * 3), rgb(size_t(n) * 3);
  // The rays' views and gains only with exposure codes (the draws are the same either way).
  const bool exposed = exposure.enabled();
  std::vector<uint32_t> views(exposed ? size_t(n) : 0);
  std::vector<float> gains(exposed ? size_t(n) * 3 : 0);
  std::mt19937_64 rng(uint64_t(o.seed) * 0x9E3779B97F4A7C15ull + uint64_t(done));
  rays.Sample(n, rng, origins.data(), dirs.data(), rgb.data(), exposed ? views.data() : nullptr);
  if (exposed) exposure.Gains(n, views.data(), gains.data());
  const float* gain = exposed ? gains.data() : nullptr;
  if (qat) qat->Apply(model);
  const PruneDecision d = TestComponents(*model, rate, lambda_e, n, origins.data(), dirs.data(),
                                         rgb.data(), o.prune_share, gain);
  // Both tests see the same model; a component's removal leaves the hidden units as they are.
  const HiddenDecision hd = TestHiddenUnits(*model, o.mlp_levels, lambda_e, n, origins.data(),
                                            dirs.data(), rgb.data(), o.prune_share, gain);
  if (qat) qat->Restore(model);
  PruneComponents(d, model, opt);  // QAT notices the new shapes and refreshes
  PruneHidden(hd, model, opt);
  const auto& dr = model->density().ranks();
  const auto& ar = model->appearance().ranks();
  std::fprintf(stderr,
               "%spruning at iteration %d (lambda_e %g): %d components and %d hidden unit pairs "
               "removed; density %d,%d,%d, appearance %d,%d,%d, head %d wide remain (%.1f s)\n",
               isatty(2) ? "\n" : "", done, lambda_e, d.dropped, hd.dropped, dr[0], dr[1], dr[2],
               ar[0], ar[1], ar[2], model->head().config().hidden, SecondsSince(start));
}

}  // namespace

TrainResult Train(const TrainOptions& o, const Dataset& train, const Dataset& test,
                  TensorfModel* model, RateState* rate_out) {
  TrainResult result;
  RateState local_rate;
  RateState& rate = rate_out ? *rate_out : local_rate;
  rate.Configure(o);
  const bool use_rate = o.lambda_e > 0.0f || o.target_bytes > 0;
  TrainOptions live = o;  // lambda_e moves under rate control
  std::unique_ptr<LambdaController> controller;
  const int rate_start = RateStartIteration(o);
  const int qat_start = QatStartIteration(o);
  QuantAwareModel qat;
  if (train.views.empty()) throw std::invalid_argument("the training split has no views");
  const auto start = Clock::now();

  // Milestones scaled to this run's length.
  std::vector<int> upsample_at, mask_at;
  for (int m : o.upsample_iters)
    upsample_at.push_back(ScaleMilestone(m, o.iters, o.reference_iters));
  for (int m : o.alpha_mask_iters) mask_at.push_back(ScaleMilestone(m, o.iters, o.reference_iters));
  const std::vector<long> voxel_counts = UpsampleVoxelCounts(o);

  const std::string ckpt_path = o.out_dir.empty() ? std::string() : o.out_dir + "/checkpoint.ckpt";
  if (o.resume && (ckpt_path.empty() || access(ckpt_path.c_str(), R_OK) != 0)) {
    throw std::runtime_error(
        "resume: no checkpoint to resume from" +
        (ckpt_path.empty() ? std::string(" (no output directory)") : " at " + ckpt_path));
  }
  int first_iter = 0;
  Checkpoint resumed_from;
  if (o.resume) {
    first_iter = LoadModelCheckpoint(ckpt_path, model, &rate, &resumed_from);
    if (o.target_bytes > 0 && rate.active && rate.checkpoint_lambda_e > 0.f) {
      // Rate control continues from the lambda_e it had reached.
      live.lambda_e = rate.checkpoint_lambda_e;
      controller = std::make_unique<LambdaController>(o.target_bytes, live.lambda_e);
    }
    std::fprintf(stderr, "resumed from %s at iteration %d\n", ckpt_path.c_str(), first_iter);
  } else {
    model->Initialize(ResolutionFor(o.voxels_init, model->config().aabb), o.seed);
  }

  RaySet rays(train.views);
  Optimizers opt;
  opt.Reset(*model);
  TrainProgress progress;
  const bool exposure_on = IsOn(o.exposure_codes, model->unbounded() || model->forward());
  progress.exposure.Reset(exposure_on ? static_cast<int>(train.views.size()) : 0);
  const CameraRefineSchedule refine = CameraRefineScheduleFor(o, train);
  // The held-out views that are scored: with refined cameras only these are aligned.
  const int scored_stride = ScoredTestViewStride(o, test.views.size());
  const std::vector<size_t> scored_views =
      EvalViews(test.views.size(), scored_stride, o.max_test_views);
  if (refine.on) {
    for (const View& v : train.views) progress.cameras.push_back(v.camera);
    rays.UseCameras(&progress.cameras);
  }
  const float tv_density = o.tv_weight_density >= 0.f ? o.tv_weight_density
                           : model->unbounded()       ? kUnboundedTvWeight
                                                      : 0.f;
  const float tv_app = o.tv_weight_app >= 0.f ? o.tv_weight_app
                       : model->unbounded()   ? kUnboundedTvWeight
                                              : 0.f;
  progress.rng.seed(o.seed);
  progress.l1_weight = o.l1_weight_initial;
  const float lr_factor = std::pow(o.lr_decay_ratio, 1.0f / float(o.iters));
  const bool exact_resume =
      o.resume && LoadTrainState(resumed_from, ckpt_path, &opt, &rate, &rays, &progress);
  resumed_from = Checkpoint();  // the arrays are in the model and the optimizers now
  // Every ray of an unbounded scene meets its cube, and a forward-facing scene's box is in NDC.
  if (!exact_resume && !model->unbounded() && !model->forward()) {
    const Aabb box = model->aabb();
    rays.Filter([&box](const float* org, const float* dir) {
      float tn, tf;
      RayAabb(box, org, dir, &tn, &tf);
      return tf > tn;
    });
  }
  if (o.resume && !exact_resume) {
    // A checkpoint from before ecrf saved the training state: continue approximately (fresh
    // optimizer moments and generator, the schedule position recomputed).
    std::fprintf(stderr,
                 "warning: %s has no training state (an older ecrf wrote it): the resumed run "
                 "will not equal an uninterrupted one\n",
                 ckpt_path.c_str());
    for (int m : mask_at) {
      if (first_iter > m) progress.l1_weight = o.l1_weight_rest;
    }
    int last_reset = 0;
    for (int m : upsample_at) {
      if (m < first_iter) last_reset = m;
    }
    opt.lr_scale = std::pow(lr_factor, float(first_iter - last_reset));
    progress.rng.seed(o.seed + uint64_t(first_iter));
  }
  float& l1_weight = progress.l1_weight;
  std::mt19937_64& rng = progress.rng;
  result.psnr_curve = progress.psnr_curve;
  const int n = o.batch_rays;
  std::vector<float> origins(size_t(n) * 3), dirs(size_t(n) * 3), rgb(size_t(n) * 3);
  std::vector<uint32_t> ray_views(exposure_on ? size_t(n) : 0);
  std::vector<float> ray_gain(ray_views.size() * 3), dl_dgain(ray_gain.size());
  double mse_sum = 0.0;
  int mse_count = 0;
  auto interval_start = Clock::now();
  TrainStepStats stats;
  double eval_seconds = 0.0;
  // Training time of this process plus what the checkpoint had accumulated.
  auto train_seconds = [&] { return progress.train_seconds + SecondsSince(start) - eval_seconds; };
  // The model with everything an exact resume needs (train_state.h).
  auto save_checkpoint = [&](int done, double seconds) {
    TrainProgress now = progress;
    now.train_seconds = seconds;
    now.psnr_curve = result.psnr_curve;
    const Checkpoint state = SaveTrainState(opt, rate, rays, now);
    SaveModelCheckpoint(ckpt_path, *model, done, live, &rate, &state, &o);
  };

  for (int it = first_iter; it < o.iters; ++it) {
    rays.NextBatch(n, rng, origins.data(), dirs.data(), rgb.data(),
                   exposure_on ? ray_views.data() : nullptr);
    if (exposure_on) progress.exposure.Gains(n, ray_views.data(), ray_gain.data());
    model->ZeroGrads();
    if (use_rate && it >= rate_start && !controller && o.target_bytes > 0) {
      const size_t float_bytes =
          sizeof(float) * (model->density().params().size() + model->appearance().params().size() +
                           model->head().params().size());
      live.lambda_e =
          o.lambda_e > 0.f ? o.lambda_e : InitialLambdaForSize(o.target_bytes, float_bytes);
      controller = std::make_unique<LambdaController>(o.target_bytes, live.lambda_e);
    }
    if (use_rate && it >= rate_start && !rate.active) {
      rate.Activate(*model, o);
      std::fprintf(stderr, "%srate objective on at iteration %d (lambda_e %g, alpha %g)\n",
                   isatty(2) ? "\n" : "", it, live.lambda_e, o.alpha);
    }
    if (controller && rate.active && it > rate_start &&
        (it - rate_start) % std::max(1, o.rate_control_every) == 0) {
      const size_t bytes = EncodeScene(*model, RunEncodeOptions(o, rate)).size();
      const float before = live.lambda_e;
      live.lambda_e = controller->Update(bytes);
      std::fprintf(
          stderr,
          "%srate control at iteration %d: file %zu bytes for a target of %zu, lambda_e %g -> %g\n",
          isatty(2) ? "\n" : "", it, bytes, o.target_bytes, before, live.lambda_e);
    }
    const bool quant_aware = it >= qat_start;
    if (quant_aware) {
      if (!rate.active) rate.Activate(*model, o);  // freezes the steps (lambda_e = 0 runs)
      if ((it - qat_start) % std::max(1, o.qat_refresh) == 0 || !qat.fresh_for(*model)) {
        if (it == qat_start) {
          std::fprintf(stderr, "%squantization-aware training from iteration %d\n",
                       isatty(2) ? "\n" : "", it);
        }
        qat.Refresh(*model, rate.steps, rate.config, o.mlp_levels, o.rounding_offset,
                    o.rdoq_lambda);
      }
      qat.Apply(model);
    }
    stats =
        TrainStep(*model, n, origins.data(), dirs.data(), rgb.data(), rng(), o.distortion_weight,
                  exposure_on ? ray_gain.data() : nullptr, exposure_on ? dl_dgain.data() : nullptr);
    qat.Restore(model);  // the gradients of Q(G) go to G unchanged (straight-through)
    // One NaN reaches every parameter within a few steps, and Adam never washes it out: stop
    // before it is applied. The head's gradient is small and sees every ray.
    if (!std::isfinite(stats.mse)) FailDiverged(it, "the loss is not finite", ckpt_path);
    if (!AllFinite(model->head().grads()))
      FailDiverged(it, "a gradient of the appearance MLP is not finite", ckpt_path);
    if (l1_weight > 0) model->DensityL1(l1_weight);
    if (tv_density > 0 || tv_app > 0) {
      const float decay = std::pow(o.lr_decay_ratio, float(it) / float(o.iters));
      if (tv_density > 0) model->density().PlaneTotalVariation(tv_density * decay);
      if (tv_app > 0) model->appearance().PlaneTotalVariation(tv_app * decay);
    }
    if (rate.active && use_rate) rate.Step(*model, live, rng());
    opt.Step(*model, o);
    if (exposure_on) {
      progress.exposure.Step(n, ray_views.data(), ray_gain.data(), dl_dgain.data(),
                             o.lr_exposure * opt.lr_scale);
    }
    opt.lr_scale *= lr_factor;
    mse_sum += stats.mse;
    ++mse_count;

    const int done = it + 1;
    if (done % o.progress_every == 0 || done == o.iters) {
      const double mse = mse_sum / std::max(1, mse_count);
      result.final_train_psnr = -10.0 * std::log10(std::max(mse, 1e-12));
      const double spi = SecondsSince(interval_start) / std::max(1, mse_count);
      PrintProgress(done, o.iters, mse, result.final_train_psnr, *model, stats, spi,
                    train_seconds(), rate.active ? rate.last_bits / 8e6 : -1.0);
      mse_sum = 0.0;
      mse_count = 0;
      interval_start = Clock::now();
    }

    if (use_rate && rate.active && PruneIteration(o, rate_start, done)) {
      PruneAt(done, live.lambda_e, o, rays, progress.exposure, quant_aware ? &qat : nullptr, model,
              &opt, rate);
    }

    // TensoRF order: alpha mask (and shrink / ray filtering) first, then upsampling.
    for (size_t k = 0; k < mask_at.size(); ++k) {
      if (it != mask_at[k]) continue;
      const Aabb new_box = model->UpdateAlphaMask(model->res());
      if (o.mask_downscale > 1) {
        model->SetAlphaMask(CoarsenAlphaMask(*model->alpha_mask(), o.mask_downscale));
      }
      if (k == 0) {
        if (!model->unbounded()) model->Shrink(new_box);  // the contracted cube is all of space
        l1_weight = o.l1_weight_rest;
        opt.Reset(*model);
      }
      if (k == 1 && !model->unbounded() && !model->forward()) {
        const TensorfModel& m = *model;
        const bool filtered = rays.FilterChunked(
            [&m](int count, const float* org, const float* dir, uint8_t* keep) {
              const std::vector<uint8_t> k = m.FilterRays(count, org, dir, false);
              std::copy(k.begin(), k.end(), keep);
            },
            size_t(o.batch_rays));
        if (filtered) {
          std::fprintf(stderr, "\nfiltered training rays: %zu of %zu remain\n", rays.size(),
                       rays.total());
        } else {
          // An empty alpha mask this early means the density has not formed yet (a very short
          // run scales the mask updates down with it); filtering would leave nothing to train on.
          std::fprintf(
              stderr,
              "\nray filtering skipped at iteration %d: the alpha mask keeps fewer rays than one "
              "batch (the model has too little density yet; more --iters give it time)\n",
              it);
        }
      }
    }
    for (size_t k = 0; k < upsample_at.size(); ++k) {
      if (it != upsample_at[k]) continue;
      model->UpsampleTo(ResolutionFor(voxel_counts[k], model->aabb()));
      opt.Reset(*model);
    }

    if (refine.Due(done)) {
      RefineCamerasRound(done, refine, *model, train.views,
                         exposure_on ? progress.exposure.log_gain().data() : nullptr,
                         o.seed + uint64_t(done), &progress.cameras, &result.camera_refinement);
    }
    if (o.eval_every > 0 && done % o.eval_every == 0 && done < o.iters) {
      const auto eval_start = Clock::now();
      // With refined cameras, the held-out ones are aligned first, as for the final score.
      const Dataset scored =
          refine.on ? WithCameras(test, AlignHeldOutCameras(*model, train, test, progress.cameras,
                                                            scored_views, o.seed, nullptr))
                    : Dataset();
      const EvalResult e =
          Evaluate(*model, refine.on ? scored : test, scored_stride, o.max_test_views, false);
      eval_seconds += SecondsSince(eval_start);
      result.psnr_curve.emplace_back(train_seconds() / 60.0, e.psnr);
      std::fprintf(stderr, "%s  test psnr %.2f dB at %.1f min (training time)\n",
                   isatty(2) ? "\n" : "", e.psnr, result.psnr_curve.back().first);
    }
    if (!ckpt_path.empty() && o.checkpoint_every > 0 && done % o.checkpoint_every == 0 &&
        done < o.iters) {
      CheckModelFinite(*model, it, ckpt_path);
      save_checkpoint(done, train_seconds());
    }
    if (o.stop_after > 0 && done == o.stop_after && done < o.iters) {
      throw TrainingStopped("training stopped after iteration " + std::to_string(done) +
                            " (--stop-after)");
    }
  }
  if (isatty(2)) std::fprintf(stderr, "\n");
  if (exposure_on) {
    const std::vector<float>& g = progress.exposure.log_gain();
    const auto [lo, hi] = std::minmax_element(g.begin(), g.end());
    std::fprintf(stderr,
                 "exposure codes: the %d training images' gains span %.3f-%.3f of the neutral "
                 "exposure the file renders\n",
                 progress.exposure.views(), std::exp(*lo), std::exp(*hi));
    result.exposure_log_gain = g;
  }
  if (refine.on) {
    result.train_cameras = progress.cameras;
    result.test_cameras = AlignHeldOutCameras(*model, train, test, progress.cameras, scored_views,
                                              o.seed, &result.camera_refinement);
  }
  result.iterations = o.iters;
  result.final_lambda_e = live.lambda_e;
  result.train_seconds = train_seconds();
  CheckModelFinite(*model, o.iters - 1, ckpt_path);
  if (!ckpt_path.empty()) save_checkpoint(o.iters, result.train_seconds);
  if (!use_rate && o.report_rate) {
    // Without the rate objective, fit an entropy model to the final grids anyway so every run
    // reports the size its coefficients would cost (the lambda_e = 0 point of a sweep).
    if (!rate.active) rate.Activate(*model, o);
    TrainOptions fit = o;
    fit.lambda_e = 0.0f;
    for (int k = 0; k < 300; ++k) rate.Step(*model, fit, rng());
  }
  if (rate.active || o.report_rate) result.rate = rate.Evaluate(*model);

  // The float model is scored on request only: the decoded file is what a user gets (and is
  // always scored by the caller); scoring both doubled the evaluation time of a default run.
  if (o.score_float) {
    result.test = Evaluate(*model, WithCameras(test, result.test_cameras), scored_stride,
                           o.max_test_views, o.save_renders);
    if (o.eval_every > 0)
      result.psnr_curve.emplace_back(result.train_seconds / 60.0, result.test.psnr);
  }
  return result;
}

}  // namespace trainer
}  // namespace ecrf
