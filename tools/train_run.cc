#include "tools/train_run.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "tools/cli_args.h"
#include "tools/decoded_scene.h"
#include "tools/encode_report.h"
#include "trainer/checkpoint.h"
#include "trainer/encode_rate_control.h"
#include "trainer/image_io.h"
#include "trainer/scene_encoder.h"
#include "trainer/trainer.h"

namespace ecrf {
namespace tools {

const char kTrainFlagsUsage[] =
    "  --preset fast|paper|tiny   schedule and grid sizes (default fast; tiny for --scene)\n"
    "  --iters N                  iterations (milestones scale with it)\n"
    "  --scene-type auto|object|unbounded|forward\n"
    "                             scene model (default auto, from the camera layout): object keeps\n"
    "                             the dataset box; unbounded contracts space around the fitted region\n"
    "                             of interest (SPEC.md 7.2.1); forward samples the NDC of the average\n"
    "                             camera, for captures whose cameras all look one way (7.2.2)\n"
    "  --downscale N              shrink the images by N (area filter)\n"
    "  --ranks D,A                density and appearance components per plane/line (fast: 16,48)\n"
    "  --final-grid N             about N^3 voxels in the box after the last upsampling (fast: 180)\n"
    "  --upsample-at I,J,...      iterations of the grid upsamplings (fast: 300,600,900,1200,1500)\n"
    "  --mask-at I,J,...          iterations of the alpha-mask updates and box shrink (fast: 300,900)\n"
    "  --mlp-hidden N             width of the appearance MLP's hidden layers (default 128)\n"
    "  --batch N                  rays per iteration (default 4096)\n"
    "  --seed N                   random seed\n"
    "  --checkpoint-every N       write RUN_DIR/checkpoint.ckpt every N iterations\n"
    "  --resume                   continue from RUN_DIR/checkpoint.ckpt (exactly as if never stopped)\n"
    "  --stop-after N             leave after N iterations (resume later with --resume)\n"
    "  --eval-every N             test PSNR every N iterations (a PSNR-vs-minutes curve)\n"
    "  --test-stride K            evaluate every K-th test view\n"
    "  --max-test-views N         evaluate at most N test views\n"
    "  --eval-downscale N         score the test views at 1/N of their size (area filter)\n"
    "  --save-renders             write the test renders as PNG into RUN_DIR/renders\n"
    "  --threads N                worker threads (default: all cores)\n"
    "ECRF objective:\n"
    "  --lambda-e X               weight of the estimated size in bits (0 = plain TensoRF)\n"
    "  --rate low|medium|high     named rate points (default medium): lambda_e 2e-10, 3e-11, 2e-11\n"
    "                             with steps x4, x3, x1 and 15, 31, 127 MLP levels (low: at most 32\n"
    "                             appearance components; low and medium with the fast preset: a final\n"
    "                             grid (11/9)^3 times larger reached at 2/3 of the upsampling\n"
    "                             iterations); other flags override a point's settings\n"
    "  --target-size SIZE         adapt lambda_e during training, then the steps at encode time, for\n"
    "                             a file of at most SIZE (e.g. 500KB, 1.2MB); the step scale, MLP\n"
    "                             levels, appearance components and grid schedule follow the nearest\n"
    "                             rate point unless given\n"
    "  --alpha A                  lambda_r = A * lambda_e for the DCT-coefficient L2 term (default 1)\n"
    "  --dct-block CxHxW          plane block shape (default 16x16x16)\n"
    "  --line-block CxL           line block shape (default 8x8)\n"
    "  --rate-fraction F          share of blocks in each step's rate estimate (default 0.1)\n"
    "  --quant-step-scale S       quantization steps S times the 8-bit peak step (default 1)\n"
    "  --rate-start F             share of the run after which the rate terms switch on (default 0.533)\n"
    "  --qat-start F              quantization-aware training from this share of the run on\n"
    "                             (never before the rate phase; 1 = off; default: the rate phase)\n"
    "  --rounding-offset X        coefficient quantizer floor(|c| / step + X), 0 < X <= 0.5, in\n"
    "                             training and encoding (default 0.5: rounding to nearest)\n"
    "  --qat-refresh N            recompute the decoded grids every N iterations (default 1)\n"
    "  --mlp-levels L             code the basis and MLP as integer levels, at most L per row\n"
    "                             (default 127; 0 = binary16)\n";

namespace {

// "I,J,...": increasing positive iterations.
std::vector<int> ParseIterationList(const char* flag, const std::string& text) {
  std::vector<int> at;
  for (size_t begin = 0; begin <= text.size();) {
    size_t end = text.find(',', begin);
    if (end == std::string::npos) end = text.size();
    at.push_back(ParseInt(flag, text.substr(begin, end - begin).c_str()));
    if (at.back() < 1 || (at.size() > 1 && at.back() <= at[at.size() - 2])) {
      throw std::invalid_argument(std::string(flag) + ": '" + text + "' is not increasing positive iterations");
    }
    begin = end + 1;
  }
  return at;
}

// Consumes argv[*i] (and its value) when it is a training flag; false otherwise.
bool ParseTrainFlag(int argc, char** argv, int* i, trainer::TrainOptions* o) {
  const std::string a = argv[*i];
  auto value = [&] { return FlagValue(argc, argv, i); };
  if (a == "--preset") {
    value();  // read before the loop
  } else if (a == "--scene") {
    trainer::SelectProceduralScene(value(), o);
  } else if (a == "--data") {
    o->data_dir = value();
  } else if (a == "--scene-type") {
    o->scene_type = value();
    trainer::CheckSceneType(o->scene_type);  // a bad name fails before the data loads
  } else if (a == "--iters") {
    o->iters = ParseInt("--iters", value());
  } else if (a == "--downscale") {
    o->downscale = std::max(1, ParseInt("--downscale", value()));
  } else if (a == "--batch") {
    o->batch_rays = std::max(1, ParseInt("--batch", value()));
  } else if (a == "--seed") {
    o->seed = uint32_t(ParseInt("--seed", value()));
  } else if (a == "--checkpoint-every") {
    o->checkpoint_every = ParseInt("--checkpoint-every", value());
  } else if (a == "--resume") {
    o->resume = true;
  } else if (a == "--stop-after") {
    o->stop_after = ParseInt("--stop-after", value());
  } else if (a == "--eval-every") {
    o->eval_every = ParseInt("--eval-every", value());
  } else if (a == "--test-stride") {
    o->test_view_stride = std::max(1, ParseInt("--test-stride", value()));
  } else if (a == "--eval-downscale") {
    o->eval_downscale = ParseInt("--eval-downscale", value());
    if (o->eval_downscale < 1) throw std::invalid_argument("--eval-downscale must be at least 1");
  } else if (a == "--max-test-views") {
    o->max_test_views = ParseInt("--max-test-views", value());
  } else if (a == "--lambda-e") {
    o->lambda_e = ParseFloat("--lambda-e", value());
  } else if (a == "--rate") {
    value();  // applied before every other flag (TrainOptionsFromArgs), so they override it
  } else if (a == "--target-size") {
    o->target_bytes = trainer::ParseByteSize(value());
  } else if (a == "--alpha") {
    o->alpha = ParseFloat("--alpha", value());
  } else if (a == "--ranks") {
    const std::string text = value();
    const size_t comma = text.find(',');
    if (comma == std::string::npos) throw std::invalid_argument("--ranks: '" + text + "' is not D,A");
    const int d = ParseInt("--ranks", text.substr(0, comma).c_str());
    const int app = ParseInt("--ranks", text.substr(comma + 1).c_str());
    if (d < 1 || d > 256 || app < 1 || app > 256) {
      throw std::invalid_argument("--ranks: '" + text + "' is not two integers in [1, 256] joined by ','");
    }
    o->density_rank = d;
    o->appearance_rank = app;
  } else if (a == "--final-grid") {
    const int n = ParseInt("--final-grid", value());
    if (n < 2 || n > 1024) throw std::invalid_argument("--final-grid: " + std::to_string(n) + " is not in [2, 1024]");
    o->voxels_final = long(n) * n * n;
    o->voxels_init = std::min(o->voxels_init, o->voxels_final);  // upsampling never shrinks
  } else if (a == "--upsample-at") {
    o->upsample_iters = ParseIterationList("--upsample-at", value());
  } else if (a == "--mask-at") {
    o->alpha_mask_iters = ParseIterationList("--mask-at", value());
  } else if (a == "--mlp-hidden") {
    o->mlp_hidden = ParseInt("--mlp-hidden", value());
    if (o->mlp_hidden < 1 || o->mlp_hidden > 1024) {  // the format's limit (SPEC.md 6.2)
      throw std::invalid_argument("--mlp-hidden: " + std::to_string(o->mlp_hidden) + " is not in [1, 1024]");
    }
  } else if (a == "--dct-block") {
    ParseShape("--dct-block", value(), 3, o->plane_block);
  } else if (a == "--line-block") {
    int shape[2];
    ParseShape("--line-block", value(), 2, shape);
    o->line_block[0] = 1;
    o->line_block[1] = shape[0];
    o->line_block[2] = shape[1];
  } else if (a == "--rate-fraction") {
    o->rate_fraction = std::min(1.0f, ParseFloat("--rate-fraction", value()));
  } else if (a == "--quant-step-scale") {
    o->quant_step_scale = ParseFloat("--quant-step-scale", value());
    if (!(o->quant_step_scale > 0.f)) throw std::invalid_argument("--quant-step-scale must be > 0");
  } else if (a == "--rate-start") {
    o->rate_start = ParseFloat("--rate-start", value());
    if (!(o->rate_start >= 0.f && o->rate_start < 1.f)) throw std::invalid_argument("--rate-start must be in [0, 1)");
  } else if (a == "--qat-start") {
    o->qat_start = ParseFloat("--qat-start", value());
  } else if (a == "--rounding-offset") {
    o->rounding_offset = ParseFloat("--rounding-offset", value());
    if (!(o->rounding_offset > 0.f && o->rounding_offset <= 0.5f)) {
      throw std::invalid_argument("--rounding-offset must be in (0, 0.5]");
    }
  } else if (a == "--qat-refresh") {
    o->qat_refresh = std::max(1, ParseInt("--qat-refresh", value()));
  } else if (a == "--mlp-levels") {
    o->mlp_levels = ParseInt("--mlp-levels", value());
  } else if (a == "--threads") {
    omp_set_num_threads(std::max(1, ParseInt("--threads", value())));
  } else if (a == "--save-renders") {
    o->save_renders = true;
  } else {
    return false;
  }
  return true;
}

}  // namespace

trainer::TrainOptions TrainOptionsFromArgs(int argc, char** argv, std::vector<int>* rest,
                                           bool rate_point_by_default) {
  std::string preset = "fast";
  bool builtin = false, preset_given = false;
  for (int i = 1; i + 1 < argc; ++i) {
    if (!std::strcmp(argv[i], "--preset")) {
      preset = argv[i + 1];
      preset_given = true;
    }
    if (!std::strcmp(argv[i], "--scene")) builtin = true;  // every procedural scene is CI-sized
  }
  if (builtin && !preset_given) preset = "tiny";
  trainer::TrainOptions o = trainer::PresetOptions(preset);
  // A rate point is a set of defaults, like the preset: it applies first, so that the flags that
  // tune it (--lambda-e, --ranks, --final-grid, --rate-start, ...) win wherever they stand.
  const char* rate_point = nullptr;
  bool rate_flag = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--rate") && i + 1 < argc) rate_point = argv[i + 1];
    for (const char* f : {"--lambda-e", "--rate", "--target-size"}) rate_flag |= !std::strcmp(argv[i], f);
  }
  if (rate_point) {
    trainer::ApplyRatePoint(rate_point, &o);
  } else if (rate_point_by_default && !rate_flag) {
    // A compressor by default: the medium rate point unless a rate flag says otherwise
    // (--lambda-e 0 trains plain TensoRF, with the 8-bit peak steps).
    trainer::ApplyRatePoint("medium", &o);
  }
  for (int i = 1; i < argc; ++i) {
    const int at = i;
    if (!ParseTrainFlag(argc, argv, &i, &o)) rest->push_back(at);
  }
  trainer::TargetSizeFlagsGiven given;
  for (int i = 1; i < argc; ++i) {
    const bool rate = !std::strcmp(argv[i], "--rate");
    given.step_scale |= rate || !std::strcmp(argv[i], "--quant-step-scale");
    given.mlp_levels |= rate || !std::strcmp(argv[i], "--mlp-levels");
    given.ranks |= rate || !std::strcmp(argv[i], "--ranks");
    for (const char* f : {"--final-grid", "--upsample-at", "--rate-start"}) {
      given.schedule |= rate || !std::strcmp(argv[i], f);
    }
  }
  trainer::ApplyTargetSizeDefaults(&o, given);
  if (o.iters < 1) throw std::invalid_argument("--iters must be at least 1");
  // Stopping on purpose keeps the work: a checkpoint is written at the stop.
  if (o.stop_after > 0 && o.checkpoint_every == 0) o.checkpoint_every = o.stop_after;
  return o;
}

nlohmann::json TrainEncodeEvaluate(const trainer::TrainOptions& o) {
  if (o.out_dir.empty()) throw std::invalid_argument("no output directory (-o RUN_DIR)");
  if (trainer::DataSource(o).empty()) throw std::invalid_argument("no data: --data DIR or --scene builtin|capture|forward");
  if (o.resume && !FileExists(o.out_dir + "/checkpoint.ckpt")) {
    throw std::invalid_argument("--resume: no checkpoint to resume from (" + o.out_dir + "/checkpoint.ckpt does not exist)");
  }
  const OutputDirectory out_dir(o.out_dir);  // before the data: a bad -o fails now

  const trainer::Dataset train = trainer::LoadTrainingViews(o, "train");
  const trainer::Dataset test = trainer::DownscaleViews(trainer::LoadTrainingViews(o, "test"), o.eval_downscale);
  std::fprintf(stderr, "data: %zu train views, %zu test views (%dx%d, scored at %dx%d)\n", train.views.size(),
               test.views.size(), train.views[0].rgb.width, train.views[0].rgb.height,
               test.views.empty() ? 0 : test.views[0].rgb.width, test.views.empty() ? 0 : test.views[0].rgb.height);
  const trainer::SceneFit fit = trainer::FitScene(o.scene_type, train);
  if (fit.model == SceneModel::kForward) {
    std::fprintf(stderr, "scene model: forward (%s); NDC box [%.3g %.3g %.3g] - [%.3g %.3g %.3g], near plane %.3g\n",
                 fit.reason.c_str(), fit.roi.min[0], fit.roi.min[1], fit.roi.min[2], fit.roi.max[0], fit.roi.max[1],
                 fit.roi.max[2], fit.ndc.near_plane);
  } else {
    std::fprintf(stderr, "scene model: %s (%s); fitted region of interest [%.3g %.3g %.3g] - [%.3g %.3g %.3g], "
                 "%.2f%% of the dataset box's volume\n",
                 SceneModelName(fit.model), fit.reason.c_str(), fit.roi.min[0], fit.roi.min[1], fit.roi.min[2],
                 fit.roi.max[0], fit.roi.max[1], fit.roi.max[2], 100 * fit.roi_share);
  }
  trainer::TensorfModel model(trainer::ConfigFor(o, train, fit));
  trainer::RateState rate;
  const trainer::TrainResult r = trainer::Train(o, train, test, &model, &rate);

  size_t float_bytes = 0;
  for (const auto& a : model.NamedParameters()) float_bytes += a.size * sizeof(float);
  // Close the loop: encode, decode with the embeddable decoder, and score the decoded stream.
  trainer::EncodeOptions eo = trainer::RunEncodeOptions(o, rate);
  eo.metadata_json = nlohmann::json{{"encoder", "ecrf"},
                                    {"data", trainer::DataSource(o)},
                                    {"preset", o.preset},
                                    {"iterations", r.iterations},
                                    {"lambda_e", r.final_lambda_e},
                                    {"alpha", o.alpha}}.dump();
  trainer::EncodeReport report;
  const auto encode_start = std::chrono::steady_clock::now();
  std::vector<uint8_t> bytes;
  double step_scale = 1.0;
  if (o.target_bytes > 0) {
    trainer::TargetSizeResult t = trainer::EncodeToTargetSize(model, eo, o.target_bytes);
    bytes = std::move(t.bytes);
    report = t.report;
    step_scale = t.step_scale;
    std::printf("target %zu bytes: lambda_e ended at %g, steps x%.4g at encode time, %zu bytes (%+.2f%%)\n",
                o.target_bytes, r.final_lambda_e, t.step_scale, bytes.size(),
                100.0 * (double(bytes.size()) / double(o.target_bytes) - 1.0));
  } else {
    bytes = trainer::EncodeScene(model, eo, &report);
  }
  const double encode_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - encode_start).count();
  trainer::WriteFileAtomically(o.out_dir + "/scene.ecrf", bytes.data(), bytes.size());
  const LoadedScene decoded = DecodeSceneBytes(std::move(bytes), o.out_dir + "/scene.ecrf",
                                                dec::GridStorage::kFloat32, kUnlimitedMemory);
  dec::RenderOptions ro;
  ro.num_threads = 0;
  const trainer::EvalResult d = EvaluateDecoded(*decoded.field, test, o.test_view_stride, o.max_test_views, ro, false);

  std::printf("trained %d iterations in %.1f s (%.3f s/it); test PSNR %.2f dB, SSIM %.4f over %d views; "
              "float32 model %.2f MB; estimated coded grids %.3f MB\n",
              r.iterations, r.train_seconds, r.train_seconds / std::max(1, r.iterations), r.test.psnr,
              r.test.ssim, r.test.views, float_bytes / 1e6, r.rate.total_bits / 8e6);
  std::printf("encoded %s/scene.ecrf: %zu bytes (%.1fx smaller than float32); decoded stream: test PSNR %.2f dB "
              "(%+.2f dB), SSIM %.4f; decode %.0f ms, render %.0f ms/view (%.1f samples, %.1f MLP samples per ray)\n",
              o.out_dir.c_str(), decoded.bytes.size(), double(float_bytes) / decoded.bytes.size(), d.psnr,
              d.psnr - r.test.psnr, d.ssim, 1e3 * decoded.decode_seconds, 1e3 * d.seconds_per_view,
              d.samples_per_ray, d.color_samples_per_ray);

  nlohmann::json m;
  m["preset"] = o.preset;
  m["data"] = trainer::DataSource(o);
  m["iterations"] = r.iterations;
  m["seed"] = o.seed;
  m["test_view_stride"] = o.test_view_stride;
  m["max_test_views"] = o.max_test_views;
  m["eval_downscale"] = o.eval_downscale;
  m["train_seconds"] = r.train_seconds;
  m["train_psnr"] = r.final_train_psnr;
  m["test_psnr"] = r.test.psnr;
  m["test_ssim"] = r.test.ssim;
  m["test_views"] = r.test.views;
  m["render_seconds_per_view"] = r.test.seconds_per_view;
  m["grid_res"] = model.res();
  m["aabb_min"] = model.aabb().min;
  m["aabb_max"] = model.aabb().max;
  m["scene_model"] = SceneModelName(fit.model);
  m["scene_model_reason"] = fit.reason;
  m["dataset_aabb_min"] = {train.scene_aabb[0][0], train.scene_aabb[0][1], train.scene_aabb[0][2]};
  m["dataset_aabb_max"] = {train.scene_aabb[1][0], train.scene_aabb[1][1], train.scene_aabb[1][2]};
  m["fitted_roi_min"] = fit.roi.min;
  m["fitted_roi_max"] = fit.roi.max;
  m["fitted_roi_volume_share"] = fit.roi_share;
  m["samples_per_ray"] = model.n_samples();  // the cap; decoded_samples_per_ray: evaluated ones
  m["float32_model_bytes"] = float_bytes;
  m["lambda_e"] = o.lambda_e;
  m["final_lambda_e"] = r.final_lambda_e;
  m["target_bytes"] = o.target_bytes;
  m["encode_step_scale"] = step_scale;
  m["alpha"] = o.alpha;
  m["quant_step_scale"] = o.quant_step_scale;
  m["rate_start"] = o.rate_start;
  m["qat_start"] = o.qat_start;
  m["qat_refresh"] = o.qat_refresh;
  m["rounding_offset"] = o.rounding_offset;
  m["mlp_levels"] = o.mlp_levels;
  m["plane_block"] = o.plane_block;
  m["line_block"] = o.line_block;
  m["file_bytes"] = decoded.bytes.size();
  m["decoded_test_psnr"] = d.psnr;
  m["decoded_test_ssim"] = d.ssim;
  m["decode_seconds"] = decoded.decode_seconds;
  m["decoded_render_seconds_per_view"] = d.seconds_per_view;
  m["decoded_samples_per_ray"] = d.samples_per_ray;
  m["decoded_mlp_samples_per_ray"] = d.color_samples_per_ray;
  m["encode_seconds"] = encode_seconds;
  m["encode"] = EncodeReportJson(report);
  m["coded_to_estimated_grid_bytes"] = r.rate.total_bits > 0 ? report.coefficient_bytes() * 8.0 / r.rate.total_bits : 0.0;
  m["estimated_grid_bits"] = r.rate.total_bits;
  m["estimated_grid_bytes"] = r.rate.total_bits / 8.0;
  nlohmann::json per_tensor = nlohmann::json::object();
  for (size_t t = 0; t < r.rate.bits.size(); ++t) {
    per_tensor[trainer::RateTensorName(int(t))] = {{"bits", r.rate.bits[t]}, {"coefficients", r.rate.coeffs[t]}};
  }
  m["estimated_bits_per_tensor"] = per_tensor;
  if (!r.psnr_curve.empty()) {
    nlohmann::json curve = nlohmann::json::array();
    for (const auto& p : r.psnr_curve) curve.push_back({{"minutes", p.first}, {"test_psnr", p.second}});
    m["psnr_curve"] = curve;
  }
  const std::string text = m.dump(2) + "\n";
  trainer::WriteFileAtomically(o.out_dir + "/metrics.json", text.data(), text.size());
  if (o.save_renders) {
    MakeDirectory(o.out_dir + "/renders");
    for (size_t i = 0; i < r.test.renders.size(); ++i) {
      char name[64];
      std::snprintf(name, sizeof(name), "/renders/test_%03zu.png", i * size_t(o.test_view_stride));
      trainer::SavePng(o.out_dir + name, r.test.renders[i]);
    }
  }
  return m;
}

}  // namespace tools
}  // namespace ecrf
