#include "tools/train_flags.h"
#include "encoder/coef_rdoq.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "tools/cli_args.h"
#include "trainer/data/scene_fit.h"
#include "trainer/train/train_options.h"

namespace ecrf {
namespace tools {
namespace {

// The value of the last `flag VALUE` or `flag=VALUE` in args, or nullptr.
const std::string* LastValue(const std::vector<std::string>& args, const std::string& flag,
                             std::string* storage) {
  const std::string* found = nullptr;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == flag && i + 1 < args.size()) {
      found = &args[i + 1];
    } else if (args[i].compare(0, flag.size() + 1, flag + "=") == 0) {
      *storage = args[i].substr(flag.size() + 1);
      found = storage;
    }
  }
  return found;
}

bool Given(const std::vector<std::string>& args, const std::string& flag) {
  std::string storage;
  return LastValue(args, flag, &storage) != nullptr;
}

// "I,J,...": increasing positive iterations.
std::vector<int> ParseIterationList(const char* flag, const std::string& text) {
  std::vector<int> at;
  for (size_t begin = 0; begin <= text.size();) {
    size_t end = text.find(',', begin);
    if (end == std::string::npos) end = text.size();
    at.push_back(ParseInt(flag, text.substr(begin, end - begin).c_str()));
    if (at.back() < 1 || (at.size() > 1 && at.back() <= at[at.size() - 2])) {
      throw std::invalid_argument(std::string(flag) + ": '" + text +
                                  "' is not increasing positive iterations");
    }
    begin = end + 1;
  }
  return at;
}

// "F,G,..." of shares (of the rate phase), each in (0, 1) and increasing; "" is the empty list.
std::vector<float> ParseShareList(const char* flag, const std::string& text) {
  std::vector<float> at;
  if (text.empty()) return at;
  for (size_t begin = 0; begin <= text.size();) {
    size_t end = text.find(',', begin);
    if (end == std::string::npos) end = text.size();
    const std::string item = text.substr(begin, end - begin);
    char* stop = nullptr;
    const double v = std::strtod(item.c_str(), &stop);
    if (item.empty() || *stop != '\0' || !(v > 0.0 && v < 1.0) ||
        (!at.empty() && !(float(v) > at.back()))) {
      throw std::invalid_argument(std::string(flag) + ": '" + text +
                                  "' is not a list of increasing shares in (0, 1)");
    }
    at.push_back(float(v));
    begin = end + 1;
  }
  return at;
}

std::string JoinInts(const std::vector<int>& v, const char* separator) {
  std::string s;
  for (size_t k = 0; k < v.size(); ++k) s += (k ? separator : "") + std::to_string(v[k]);
  return s;
}

std::string FloatText(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", v);
  return text;
}

int FinalGridEdge(const trainer::TrainOptions& o) {
  return int(std::lround(std::cbrt(double(o.voxels_final))));
}

}  // namespace

trainer::TrainOptions BaseTrainOptions(const std::vector<std::string>& args) {
  std::string storage;
  const std::string* preset = LastValue(args, "--preset", &storage);
  const bool procedural = Given(args, "--scene");  // every procedural scene is CI-sized
  trainer::TrainOptions o = trainer::PresetOptions(preset ? *preset : procedural ? "tiny" : "fast");
  std::string rate_storage, lambda_storage;
  const std::string* rate = LastValue(args, "--rate", &rate_storage);
  const std::string* lambda = LastValue(args, "--lambda-e", &lambda_storage);
  if (rate) {
    trainer::ApplyRatePoint(*rate, &o);
  } else if (lambda && std::strtod(lambda->c_str(), nullptr) == 0.0) {
    trainer::ApplyRatePoint("none", &o);  // --lambda-e 0: plain TensoRF, as documented
  } else if (!Given(args, "--target-size")) {
    trainer::ApplyRatePoint("medium", &o);  // a compressor by default
  }
  return o;
}

void AddTrainFlags(CLI::App* app, TrainFlags* f) {
  trainer::TrainOptions& o = f->options;
  app->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  f->preset = o.preset;
  f->rate = o.rate_point;
  f->final_grid = FinalGridEdge(o);
  f->ranks = std::to_string(o.density_rank) + "," + std::to_string(o.appearance_rank);
  f->dct_block = JoinInts({o.plane_block[0], o.plane_block[1], o.plane_block[2]}, "x");
  f->line_block = JoinInts({o.line_block[1], o.line_block[2]}, "x");
  f->upsample_at = JoinInts(o.upsample_iters, ",");
  f->mask_at = JoinInts(o.alpha_mask_iters, ",");

  const char* data = "Data";
  app->add_option("--data", o.data_dir,
                  "posed images: NeRF Blender, Instant-NGP / nerfstudio or LLFF")
      ->type_name("DIR")
      ->group(data);
  app->add_option("--scene", f->scene, "a procedural scene instead of --data (no files needed)")
      ->check(CLI::IsMember({"builtin", "capture", "capture-sparse", "forward"}))
      ->group(data);
  app->add_option(
         "--scene-type", o.scene_type,
         "scene model: object keeps the dataset box; unbounded contracts space around the fitted "
         "region of interest (SPEC.md 7.2.1); forward samples the NDC of the average camera "
         "(7.2.2); "
         "auto picks from the camera layout")
      ->check(CLI::IsMember({"auto", "object", "unbounded", "forward"}))
      ->capture_default_str()
      ->group(data);
  app->add_option("--downscale", o.downscale,
                  "shrink the training and test images by N (area filter)")
      ->type_name("N")
      ->check(CLI::Range(1, 64))
      ->capture_default_str()
      ->group(data);

  const char* schedule = "Schedule and model";
  app->add_option("--preset", f->preset, "schedule and grid sizes (tiny: the default for --scene)")
      ->check(CLI::IsMember({"fast", "paper", "tiny"}))
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--iters", o.iters, "iterations (the milestones scale with it)")
      ->type_name("N")
      ->check(CLI::Range(1, 100000000))
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--batch", o.batch_rays, "rays per iteration")
      ->type_name("N")
      ->check(CLI::Range(1, 1 << 24))
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--ranks", f->ranks,
                  "density and appearance components per plane and line, each in [1, 256]")
      ->type_name("D,A")
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--final-grid", f->final_grid,
                  "about N^3 voxels in the box after the last upsampling")
      ->type_name("N")
      ->check(CLI::Range(2, 1024))
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--upsample-at", f->upsample_at, "iterations of the grid upsamplings")
      ->type_name("I,J,...")
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--mask-downscale", o.mask_downscale,
                  "alpha-mask grid points N grid cells apart (a smaller OCCU chunk, more samples "
                  "evaluated)")
      ->type_name("N")
      ->check(CLI::Range(1, 16))
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--distortion-loss", o.distortion_weight,
                  "weight of mip-NeRF 360's distortion loss, against floaters (0: off)")
      ->type_name("W")
      ->check(CLI::Range(0.0, 10.0))
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--tv-density", o.tv_weight_density,
                  "weight of total variation on the density planes (TensoRF's TV_weight_density; "
                  "0: off; auto: 1 for unbounded scenes, 0 for the others)")
      ->type_name("W")
      ->check(CLI::Range(0.0, 1000.0))
      ->default_str("auto")
      ->group(schedule);
  app->add_option("--exposure-codes", o.exposure_codes,
                  "learn a gain per training image and channel (auto exposure, white balance), "
                  "left out of the file; auto: on for unbounded and forward-facing scenes")
      ->type_name("auto|on|off")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--lr-exposure", o.lr_exposure, "learning rate of the exposure codes")
      ->type_name("LR")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--refine-cameras", o.refine_cameras,
                  "refine the cameras (poses and shared intrinsics) against the field while "
                  "training, and align the held-out cameras before scoring; auto: on for datasets "
                  "with estimated poses (Instant-NGP / nerfstudio, LLFF, ecrf prepare)")
      ->type_name("auto|on|off")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--refine-cameras-every", o.refine_cameras_every,
                  "refine the cameras every N iterations, from 20 % to 80 % of the run (0: "
                  "iterations / 50)")
      ->type_name("N")
      ->check(CLI::Range(0, 100000000))
      ->default_str("0")
      ->group(schedule);
  app->add_option("--camera-warmup-iters", o.camera_warmup_iters,
                  "when the cameras are refined: first train a field for N iterations and refine "
                  "the cameras against it, then train the run's field afresh from those cameras "
                  "(RUN_DIR/warmup/; -1: iterations / 2, 0: no warm-up)")
      ->type_name("N")
      ->check(CLI::Range(-1, 100000000))
      ->default_str("-1")
      ->group(schedule);
  app->add_option("--weight-threshold", o.weight_threshold,
                  "colour (run the MLP on) only samples of larger weight, in training and in the "
                  "file; auto: 0.003 for unbounded scenes, 1e-4 (TensoRF) for the others")
      ->type_name("W")
      ->check(CLI::Range(0.0, 0.5))
      ->default_str("auto")
      ->group(schedule);
  app->add_option("--tv-app", o.tv_weight_app,
                  "weight of total variation on the appearance planes (TensoRF's TV_weight_app; "
                  "auto as --tv-density)")
      ->type_name("W")
      ->check(CLI::Range(0.0, 1000.0))
      ->default_str("auto")
      ->group(schedule);
  app->add_option("--mask-at", f->mask_at, "iterations of the alpha-mask updates and box shrink")
      ->type_name("I,J,...")
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--mlp-hidden", o.mlp_hidden,
                  "width of the appearance MLP's hidden layers (SPEC.md 6.2 limit)")
      ->type_name("N")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str()
      ->group(schedule);
  app->add_option("--seed", o.seed, "random seed")
      ->type_name("N")
      ->capture_default_str()
      ->group(schedule);

  const char* rate = "ECRF objective (defaults: the chosen rate point)";
  app->add_option("--rate", f->rate,
                  "rate point, the base the other flags adjust: low, medium and high trade size "
                  "for PSNR; none is "
                  "plain TensoRF (lambda_e 0). Default medium, none for --lambda-e 0, the nearest "
                  "point's settings "
                  "for --target-size")
      ->check(CLI::IsMember({"low", "medium", "high", "none"}))
      ->capture_default_str()
      ->group(rate);
  app->add_option("--lambda-e", o.lambda_e,
                  "weight of the estimated size in bits (changes only lambda_e; 0 without --rate: "
                  "plain TensoRF)")
      ->type_name("X")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str()
      ->group(rate);
  app->add_option("--target-size", f->target_size,
                  "adapt lambda_e while training, then the steps when encoding, for a file of at "
                  "most SIZE (units "
                  "B, KB, MB, KiB, MiB); steps, MLP levels, components and grid schedule follow "
                  "the nearest rate "
                  "point unless given")
      ->type_name("SIZE")
      ->group(rate);
  app->add_option("--quant-step-scale", o.quant_step_scale,
                  "quantization steps S times the 8-bit peak step (> 0)")
      ->type_name("S")
      ->capture_default_str()
      ->group(rate);
  app->add_option("--density-step-factor", o.density_step_factor,
                  "the density tensors' steps F times what --quant-step-scale gives them (> 0)")
      ->type_name("F")
      ->capture_default_str()
      ->group(rate);
  app->add_option("--mlp-levels", o.mlp_levels,
                  "code the basis and MLP as integer levels, at most L per row (0 = binary16)")
      ->type_name("L")
      ->check(CLI::Range(0, 32767))
      ->capture_default_str()
      ->group(rate);
  app->add_option("--alpha", o.alpha, "lambda_r = A * lambda_e for the DCT-coefficient L2 term")
      ->type_name("A")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str()
      ->group(rate);
  app->add_option(
         "--rate-start", o.rate_start,
         "share of the run after which the rate terms switch on, in [0, 1) (never before the last "
         "upsampling and mask update)")
      ->type_name("F")
      ->capture_default_str()
      ->group(rate);
  app->add_option("--qat-start", o.qat_start,
                  "quantization-aware training from this share of the run (< 0: with the rate "
                  "phase; >= 1: off)")
      ->type_name("F")
      ->capture_default_str()
      ->group(rate);
  app->add_option("--qat-refresh", o.qat_refresh, "recompute the decoded grids every N iterations")
      ->type_name("N")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str()
      ->group(rate);
  app->add_option(
         "--rounding-offset", o.rounding_offset,
         "coefficient quantizer floor(|c| / step + X), 0 < X <= 0.5, in training and encoding")
      ->type_name("X")
      ->capture_default_str()
      ->group(rate);
  app->add_option("--rdoq", o.rdoq_lambda,
                  "rate-distortion optimised quantization with lambda L (squared steps per bit; "
                  "0 = off), in training and encoding")
      ->type_name("L")
      ->capture_default_str()
      ->group(rate);
  app->add_option("--prune-at", f->prune_at,
                  "shares of the rate phase after which the components that cost more (lambda_e x "
                  "bits) than they give (MSE) are removed, e.g. 0.2,0.4 (empty: never)")
      ->type_name("F,...")
      ->group(rate);
  app->add_option("--prune-share", o.prune_share,
                  "the most of one mode's components a pruning test removes, in (0, 1]")
      ->type_name("S")
      ->capture_default_str()
      ->group(rate);
  app->add_option("--dct-block", f->dct_block, "plane block shape, powers of two <= 32")
      ->type_name("CxHxW")
      ->capture_default_str()
      ->group(rate);
  app->add_option("--line-block", f->line_block, "line block shape, powers of two <= 32")
      ->type_name("CxL")
      ->capture_default_str()
      ->group(rate);
  app->add_option("--rate-fraction", o.rate_fraction,
                  "share of blocks in each step's rate estimate, in (0, 1]")
      ->type_name("F")
      ->capture_default_str()
      ->group(rate);

  const char* run = "Evaluation and bookkeeping (no effect on the file)";
  app->add_option(
         "--test-stride", o.test_view_stride,
         "score every K-th test view; 0: every K-th with the smallest K that keeps at most " +
             std::to_string(trainer::kDefaultScoredTestViews) + " views (1 scores all)")
      ->type_name("K")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str()
      ->group(run);
  app->add_option("--max-test-views", o.max_test_views, "score at most N test views (0 = no limit)")
      ->type_name("N")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str()
      ->group(run);
  app->add_option("--eval-downscale", o.eval_downscale,
                  "score the test views at 1/N of their size (area filter)")
      ->type_name("N")
      ->check(CLI::Range(1, 64))
      ->capture_default_str()
      ->group(run);
  app->add_flag("--score-float", o.score_float,
                "also score the float model before encoding, on the same views (as long again)")
      ->group(run);
  app->add_option("--eval-every", o.eval_every,
                  "score the float model every N iterations (a PSNR-vs-minutes curve)")
      ->type_name("N")
      ->check(CLI::Range(0, 100000000))
      ->capture_default_str()
      ->group(run);
  app->add_flag("--save-renders", o.save_renders,
                "write the scored renders as PNG into RUN_DIR/renders")
      ->group(run);
  app->add_option("--checkpoint-every", o.checkpoint_every,
                  "write RUN_DIR/checkpoint.ckpt every N iterations")
      ->type_name("N")
      ->check(CLI::Range(0, 100000000))
      ->capture_default_str()
      ->group(run);
  app->add_flag("--resume", o.resume,
                "continue from RUN_DIR/checkpoint.ckpt (exactly as if never stopped)")
      ->group(run);
  app->add_flag("--accept-config-change", o.accept_config_change,
                "with --resume: continue although settings differ from the checkpoint's")
      ->group(run);
  app->add_flag("--overwrite", o.overwrite,
                "replace the run RUN_DIR already holds (without it, or --resume, such a RUN_DIR "
                "is refused)")
      ->group(run);
  app->add_option("--stop-after", o.stop_after,
                  "leave after N iterations (continue later with --resume)")
      ->type_name("N")
      ->check(CLI::Range(0, 100000000))
      ->capture_default_str()
      ->group(run);
  AddThreadsFlag(app, &f->threads)->group(run);
}

trainer::TrainOptions FinishTrainFlags(const CLI::App& app, TrainFlags* f) {
  trainer::TrainOptions& o = f->options;
  auto given = [&](const char* flag) { return app.count(flag) > 0; };
  if (given("--scene")) trainer::SelectProceduralScene(f->scene, &o);
  if (given("--ranks")) {
    const size_t comma = f->ranks.find(',');
    if (comma == std::string::npos)
      throw std::invalid_argument("--ranks: '" + f->ranks + "' is not D,A");
    const int d = ParseInt("--ranks", f->ranks.substr(0, comma).c_str());
    const int a = ParseInt("--ranks", f->ranks.substr(comma + 1).c_str());
    if (d < 1 || d > 256 || a < 1 || a > 256) {
      throw std::invalid_argument("--ranks: '" + f->ranks +
                                  "' is not two integers in [1, 256] joined by ','");
    }
    o.density_rank = d;
    o.appearance_rank = a;
  }
  if (given("--final-grid")) {
    o.voxels_final = long(f->final_grid) * f->final_grid * f->final_grid;
    o.voxels_init = std::min(o.voxels_init, o.voxels_final);  // upsampling never shrinks
  }
  if (given("--upsample-at"))
    o.upsample_iters = ParseIterationList("--upsample-at", f->upsample_at);
  if (given("--mask-at")) o.alpha_mask_iters = ParseIterationList("--mask-at", f->mask_at);
  if (given("--prune-at")) o.prune_at = ParseShareList("--prune-at", f->prune_at);

  if (!(o.prune_share > 0.f && o.prune_share <= 1.f))
    throw std::invalid_argument("--prune-share must be in (0, 1]");
  if (given("--dct-block")) ParseShape("--dct-block", f->dct_block, 3, o.plane_block);
  if (given("--line-block")) {
    int shape[2];
    ParseShape("--line-block", f->line_block, 2, shape);
    o.line_block[0] = 1;
    o.line_block[1] = shape[0];
    o.line_block[2] = shape[1];
  }
  if (given("--target-size")) o.target_bytes = ParseSizeWithUnit("--target-size", f->target_size);
  if (!(o.quant_step_scale > 0.f)) throw std::invalid_argument("--quant-step-scale must be > 0");
  if (!(o.density_step_factor > 0.f) || !std::isfinite(o.density_step_factor))
    throw std::invalid_argument("--density-step-factor must be > 0");
  if (!(o.rate_start >= 0.f && o.rate_start < 1.f))
    throw std::invalid_argument("--rate-start must be in [0, 1)");
  if (!(o.rounding_offset > 0.f && o.rounding_offset <= 0.5f)) {
    throw std::invalid_argument("--rounding-offset must be in (0, 0.5]");
  }
  if (!(o.rdoq_lambda >= 0.f && o.rdoq_lambda <= trainer::kMaxRdoqLambda)) {
    throw std::invalid_argument("--rdoq must be in [0, " +
                                std::to_string(int(trainer::kMaxRdoqLambda)) + "]");
  }
  if (!(o.rate_fraction > 0.f && o.rate_fraction <= 1.f))
    throw std::invalid_argument("--rate-fraction must be in (0, 1]");
  trainer::CheckSceneType(o.scene_type);

  // --target-size picks the settings the line did not give (a rate point counts as giving all).
  trainer::TargetSizeFlagsGiven settings_given;
  const bool rate = given("--rate");
  settings_given.step_scale = rate || given("--quant-step-scale");
  settings_given.mlp_levels = rate || given("--mlp-levels");
  settings_given.ranks = rate || given("--ranks");
  settings_given.schedule =
      rate || given("--final-grid") || given("--upsample-at") || given("--rate-start");
  settings_given.iters = rate || given("--iters");
  trainer::ApplyTargetSizeDefaults(&o, settings_given);
  // Stopping on purpose keeps the work: a checkpoint is written at the stop.
  if (o.stop_after > 0 && o.checkpoint_every == 0) o.checkpoint_every = o.stop_after;
  ApplyThreads(f->threads);
  return o;
}

int ParseTrainCommandLine(CLI::App* app, TrainFlags* flags, int argc, char** argv,
                          trainer::TrainOptions* options) {
  if (const int rc = ParseCommandLine(app, argc, argv); rc >= 0) return rc;
  try {
    *options = FinishTrainFlags(*app, flags);
  } catch (const std::invalid_argument& e) {
    return UsageError(*app, e.what());
  }
  return -1;
}

trainer::TrainOptions ResolveTrainOptions(const std::vector<std::string>& args) {
  auto app = MakeCommand("train", "train a model");
  TrainFlags flags;
  flags.options = BaseTrainOptions(args);
  AddTrainFlags(app.get(), &flags);
  app->add_option("-o,--out", flags.options.out_dir, "run directory");
  if (!ParseArguments(app.get(), args))
    throw std::invalid_argument("--help is not a configuration");
  return FinishTrainFlags(*app, &flags);
}

std::string DescribeSettings(const trainer::TrainOptions& o) {
  std::string s = "preset " + o.preset + ", rate point " + o.rate_point;
  if (o.target_bytes > 0) s += ", target " + std::to_string(o.target_bytes) + " B";
  s += "; lambda_e " + FloatText(o.lambda_e) + ", steps x" + FloatText(o.quant_step_scale) +
       (o.density_step_factor != 1.f
            ? " (density x" + FloatText(o.quant_step_scale * o.density_step_factor) + ")"
            : std::string()) +
       ", " +
       (o.mlp_levels > 0 ? std::to_string(o.mlp_levels) + " MLP levels"
                         : std::string("binary16 MLP")) +
       ", ranks " + std::to_string(o.density_rank) + "," + std::to_string(o.appearance_rank) +
       ", final grid " + std::to_string(FinalGridEdge(o)) + "^3, upsampling at " +
       JoinInts(o.upsample_iters, ",") + " of " + std::to_string(o.iters) +
       " iterations, rate terms from " + FloatText(o.rate_start) + " of the run";
  return s;
}

}  // namespace tools
}  // namespace ecrf
