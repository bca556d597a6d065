#include "tools/train_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include "encoder/encode_rate_control.h"
#include "encoder/scene_encoder.h"
#include "tools/camera_path_json.h"
#include "tools/cli_args.h"
#include "tools/decoded_scene.h"
#include "tools/encode_report.h"
#include "tools/encode_run.h"
#include "tools/train_flags.h"
#include "trainer/data/file_io.h"
#include "trainer/data/image_io.h"
#include "trainer/train/camera_warmup.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/eval_progress.h"
#include "trainer/train/stop_signal.h"
#include "trainer/train/train_config.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {

namespace {

std::string FormatDb(double db) {
  char text[32];
  std::snprintf(text, sizeof(text), "%+.2f dB", db);
  return text;
}

// --resume continues the run the checkpoint holds: a changed setting would silently train a
// different model from iteration N on, so it is refused unless the user accepts it.
// A run stopped before its main pass wrote a checkpoint (in its camera warm-up, which keeps its
// own) is checked against the run's config.json instead.
void CheckResumedSettings(const trainer::TrainOptions& o) {
  std::string path = o.out_dir + "/checkpoint.ckpt";
  trainer::CheckpointRunInfo info;
  if (FileExists(path)) {
    info = trainer::ReadCheckpointRunInfo(path);
  } else {
    path = o.out_dir + "/config.json";
    const std::vector<uint8_t> text = trainer::ReadWholeFile(path);
    info.config = trainer::TrainConfigFromJson(std::string(text.begin(), text.end()), path);
    info.has_config = true;
  }
  if (!info.has_config) {
    std::fprintf(
        stderr,
        "warning: %s stores no configuration (an older ecrf wrote it): settings not checked\n",
        path.c_str());
    return;
  }
  const std::vector<std::string> changed = trainer::ChangedSettings(info.config, o);
  if (changed.empty()) return;
  std::string list;
  for (const std::string& c : changed) list += "\n  " + c;
  if (!o.accept_config_change) {
    throw std::invalid_argument(
        "--resume: these settings differ from the run's (" + path + "):" + list +
        "\nresume with the run's settings (see " + o.out_dir +
        "/config.json), or add --accept-config-change to continue with the new ones");
  }
  std::fprintf(stderr, "--resume with changed settings (--accept-config-change):%s\n",
               list.c_str());
}

// A finished or started run is work a second `ecrf train -o` into its directory would silently
// replace: refused, naming what is there, unless the user resumes or overwrites it.
std::string RunFilesIn(const std::string& out_dir) {
  std::string found;
  for (const char* name : {"checkpoint.ckpt", "scene.ecrf", "metrics.json", "config.json"}) {
    if (FileExists(out_dir + "/" + name)) found += std::string(found.empty() ? "" : ", ") + name;
  }
  return found;
}

void RefuseExistingRun(const std::string& out_dir) {
  const std::string found = RunFilesIn(out_dir);
  if (found.empty()) return;
  throw std::invalid_argument(out_dir + " already holds a run (" + found +
                              "): --resume continues it, --overwrite replaces it, or choose "
                              "another -o");
}

// The scene model and region of interest FitScene chose, for the log.
void PrintSceneFit(const trainer::SceneFit& fit) {
  if (fit.model == SceneModel::kForward) {
    std::fprintf(
        stderr,
        "scene model: forward (%s); NDC box [%.3g %.3g %.3g] - [%.3g %.3g %.3g], near plane %.3g\n",
        fit.reason.c_str(), fit.roi.min[0], fit.roi.min[1], fit.roi.min[2], fit.roi.max[0],
        fit.roi.max[1], fit.roi.max[2], fit.ndc.near_plane);
  } else {
    std::fprintf(
        stderr,
        "scene model: %s (%s); fitted region of interest [%.3g %.3g %.3g] - [%.3g %.3g %.3g], "
        "%.2f%% of the dataset box's volume\n",
        SceneModelName(fit.model), fit.reason.c_str(), fit.roi.min[0], fit.roi.min[1],
        fit.roi.min[2], fit.roi.max[0], fit.roi.max[1], fit.roi.max[2], 100 * fit.roi_share);
  }
}

// Refuses a run that cannot start before anything is loaded: no -o or data, --resume without a
// checkpoint or with changed settings, or another run already in -o.
void CheckRunCanStart(const trainer::TrainOptions& options) {
  if (options.out_dir.empty()) throw std::invalid_argument("no output directory (-o RUN_DIR)");
  if (trainer::DataSource(options).empty()) {
    throw std::invalid_argument("no data: --data DIR or --scene " +
                                trainer::NameList<trainer::ProceduralScene>());
  }
  if (options.resume && !FileExists(options.out_dir + "/checkpoint.ckpt") &&
      !FileExists(trainer::CameraWarmupDir(options) + "/checkpoint.ckpt")) {
    const std::string found = RunFilesIn(options.out_dir);
    throw std::invalid_argument(
        "--resume: " + options.out_dir + " has no checkpoint.ckpt to continue from" +
        (found.empty() ? " (it holds no run): start the run without --resume"
                       : " (it holds " + found +
                             ": the run stopped before its first checkpoint): start it again "
                             "with --overwrite"));
  }
  if (options.resume) CheckResumedSettings(options);
  if (!options.resume && !options.overwrite) RefuseExistingRun(options.out_dir);
}

// The views loaded and which test views are scored (o.test_view_stride is the one in effect,
// options the one asked for), for the log.
void PrintViews(const trainer::TrainOptions& options, const trainer::TrainOptions& o,
                const trainer::Dataset& train, const trainer::Dataset& test) {
  const int scored_views =
      trainer::EvalViewCount(test.views.size(), o.test_view_stride, o.max_test_views);
  std::fprintf(stderr, "data: %zu train views, %zu test views (%dx%d, scored at %dx%d)\n",
               train.views.size(), test.views.size(), train.views[0].rgb.width,
               train.views[0].rgb.height, test.views.empty() ? 0 : test.views[0].rgb.width,
               test.views.empty() ? 0 : test.views[0].rgb.height);
  const std::string rule =
      options.test_view_stride > 0
          ? ""
          : ", evenly spaced, at most " + std::to_string(trainer::kDefaultScoredTestViews);
  std::fprintf(stderr,
               "scoring %d of %zu test views (every %d%s%s; --test-stride 1 scores all)%s\n",
               scored_views, test.views.size(), o.test_view_stride,
               o.test_view_stride == 1 ? "st" : "th", rule.c_str(),
               o.score_float ? "; the float model too (--score-float)" : "; the decoded file only");
}

// Written once the data has loaded: a run that fails before that leaves no directory behind.
void WriteRunConfig(const trainer::TrainOptions& options) {
  const std::string config = trainer::TrainConfigToJson(options) + "\n";
  trainer::WriteFileAtomically(options.out_dir + "/config.json", config.data(), config.size());
  std::fprintf(stderr,
               "configuration: %s/config.json (--print-config prints it without training)\n",
               options.out_dir.c_str());
}

// The trained model closed into a loop: encoded, decoded with the embeddable decoder, and the
// decoded stream scored.
struct CodedRun {
  encoder::EncodeReport report;
  double step_scale = 1.0;  // encode-time factor on every step (1 without a target)
  double encode_seconds = 0.0;
  LoadedScene decoded;
  trainer::EvalResult eval;  // the decoded file's scores on the test views
  // With exposure codes or refined cameras, `eval` fits them on each view's left half and scores
  // its right half; `as_given` scores whole views with the held-out cameras unaligned (the
  // dataset's, or carried through a camera warm-up) at the file's own exposure (what tables that
  // keep the dataset's poses report, LLFF's). views 0: not scored.
  trainer::EvalResult as_given;
};

void EncodeDecodeEvaluate(const trainer::TrainOptions& o, const trainer::TensorfModel& model,
                          const trainer::RateState& rate, const trainer::TrainResult& r,
                          const trainer::Dataset& test, CodedRun* coded) {
  const auto encode_start = std::chrono::steady_clock::now();
  EncodedRun encoded = EncodeRun(
      model, TrainedRunEncodeOptions(o, rate, r.iterations, r.final_lambda_e), o.target_bytes);
  std::vector<uint8_t> bytes = std::move(encoded.bytes);
  coded->report = encoded.report;
  coded->step_scale = encoded.step_scale;
  if (o.target_bytes > 0) {
    std::printf(
        "target %zu bytes: lambda_e ended at %g, steps x%.4g at encode time, %zu bytes (%+.2f%%)\n",
        o.target_bytes, r.final_lambda_e, coded->step_scale, bytes.size(),
        100.0 * (double(bytes.size()) / double(o.target_bytes) - 1.0));
  }
  coded->encode_seconds = trainer::SecondsSince(encode_start);
  trainer::WriteFileAtomically(o.out_dir + "/scene.ecrf", bytes.data(), bytes.size());
  coded->decoded = DecodeSceneBytes(std::move(bytes), o.out_dir + "/scene.ecrf",
                                    dec::GridStorage::kFloat32, kUnlimitedMemory);
  dec::RenderOptions ro;
  ro.num_threads = 0;
  // With refined cameras the held-out views are scored from their cameras aligned to the field;
  // with exposure codes (left out of the file) each view's gain is fitted on its left half.
  trainer::Dataset scored = trainer::WithCameras(test, r.test_cameras);
  const bool exposure = !r.exposure_log_gain.empty();
  if (exposure) scored = trainer::WithExposureFit(std::move(scored));
  coded->eval = EvaluateDecoded(*coded->decoded.field, scored, o.test_view_stride, o.max_test_views,
                                ro, o.save_renders);
  if (exposure || !r.test_cameras.empty()) {
    coded->as_given = EvaluateDecoded(*coded->decoded.field, test, o.test_view_stride,
                                      o.max_test_views, ro, false);
  }
}

void PrintRunSummary(const trainer::TrainOptions& o, const trainer::TrainResult& r,
                     size_t float_bytes, const CodedRun& coded) {
  const trainer::EvalResult& d = coded.eval;
  std::printf(
      "trained %d iterations in %.1f s (%.3f s/it); float32 model %.2f MB; estimated coded grids "
      "%.3f MB\n",
      r.iterations, r.train_seconds, r.train_seconds / std::max(1, r.iterations), float_bytes / 1e6,
      r.rate.total_bits / 8e6);
  if (o.score_float) {
    std::printf("float model: test PSNR %.2f dB, SSIM %.4f over %d views\n", r.test.psnr,
                r.test.ssim, r.test.views);
  }
  const std::string versus =
      o.score_float ? " (" + FormatDb(d.psnr - r.test.psnr) + " against the float model)" : "";
  const std::string scoring =
      d.fitted_columns > 0 ? " (" + trainer::HeldOutScoring(d, !r.test_cameras.empty()) + ")" : "";
  std::printf(
      "encoded %s/scene.ecrf: %zu bytes (%.1fx smaller than float32); decoded file: test PSNR %.2f "
      "dB%s, "
      "SSIM %.4f over %d views%s; decode %.0f ms, render %.0f ms/view (%s head: %.1f samples, "
      "%.1f coloured samples per ray, %.0f k multiply-adds per pixel)\n",
      o.out_dir.c_str(), coded.decoded.bytes.size(),
      double(float_bytes) / coded.decoded.bytes.size(), d.psnr, versus.c_str(), d.ssim, d.views,
      scoring.c_str(), 1e3 * coded.decoded.decode_seconds, 1e3 * d.seconds_per_view,
      AppearanceName(coded.decoded.info.head, coded.decoded.info.header.hidden), d.samples_per_ray,
      d.color_samples_per_ray, d.work_per_pixel / 1e3);
  if (coded.as_given.views > 0) {
    std::printf(
        "decoded file, whole views with unaligned held-out cameras at the file's exposure: test "
        "PSNR %.2f dB, SSIM %.4f over %d views\n",
        coded.as_given.psnr, coded.as_given.ssim, coded.as_given.views);
  }
}

// What a run trained: its settings, the model it ended with, the scene fit, the float model's
// scores and the rate estimate of its grids.
nlohmann::json TrainingMetrics(const trainer::TrainOptions& o, const trainer::TrainResult& r,
                               const trainer::TensorfModel& model, const trainer::SceneFit& fit,
                               const trainer::Dataset& train, bool warmed_up) {
  nlohmann::json m;
  m["preset"] = trainer::NameOf(o.preset);
  m["data"] = trainer::DataSource(o);
  m["iterations"] = r.iterations;
  m["camera_warmup_iters"] = warmed_up ? trainer::CameraWarmupIterations(o, train) : 0;
  m["seed"] = o.seed;
  m["test_view_stride"] = o.test_view_stride;
  m["max_test_views"] = o.max_test_views;
  m["eval_downscale"] = o.eval_downscale;
  m["train_seconds"] = r.train_seconds;
  m["train_psnr"] = r.final_train_psnr;
  // The float model's scores when --score-float asked for them (null otherwise).
  m["test_psnr"] = o.score_float ? nlohmann::json(r.test.psnr) : nlohmann::json();
  m["test_ssim"] = o.score_float ? nlohmann::json(r.test.ssim) : nlohmann::json();
  m["render_seconds_per_view"] =
      o.score_float ? nlohmann::json(r.test.seconds_per_view) : nlohmann::json();
  m["rate_point"] = trainer::NameOf(o.rate_point);
  m["grid_res"] = model.res();
  // The components the model ended with, per mode (--prune-at removes what does not pay).
  m["density_ranks"] = model.density().ranks();
  m["appearance_ranks"] = model.appearance().ranks();
  m["mlp_hidden"] = model.head().config().hidden;
  m["mlp_layers"] = model.head().config().hidden_layers;
  if (r.head_choice.iteration >= 0) {  // --head auto: what it predicted and chose
    const trainer::HeadChoiceReport& h = r.head_choice;
    nlohmann::json candidates = nlohmann::json::array();
    for (const trainer::RenderCandidate& c : h.candidates) {
      candidates.push_back({{"head", c.sh_degree >= 0 ? kShHeadName : HeadKindName(c.head)},
                            {"sh_degree", c.sh_degree},
                            {"step_ratio", c.step_ratio},
                            {"samples_per_ray", c.counts.samples},
                            {"coloured_samples_per_ray", c.counts.coloured},
                            {"coloured_ray_share", c.counts.coloured_rays},
                            {"predicted_work_per_pixel", c.work}});
    }
    m["head_choice"] = {
        {"iteration", h.iteration},
        {"render_budget", h.budget},
        {"candidates", candidates},
        {"chosen", h.choice().sh_degree >= 0 ? kShHeadName : HeadKindName(h.choice().head)},
        {"step_ratio", h.choice().step_ratio},
        {"reason", h.reason}};
  }
  m["step_ratio"] = model.config().step_ratio;
  m["prune_at"] = o.prune_at;
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
  m["lambda_e"] = o.lambda_e;
  m["final_lambda_e"] = r.final_lambda_e;
  m["target_bytes"] = o.target_bytes;
  m["alpha"] = o.alpha;
  m["quant_step_scale"] = o.quant_step_scale;
  m["rate_start"] = o.rate_start;
  m["qat_start"] = o.qat_start;
  m["qat_refresh"] = o.qat_refresh;
  m["rounding_offset"] = o.rounding_offset;
  m["rdoq_lambda"] = o.rdoq_lambda;
  m["mlp_levels"] = o.mlp_levels;
  m["plane_block"] = o.plane_block;
  m["line_block"] = o.line_block;
  m["estimated_grid_bits"] = r.rate.total_bits;
  m["estimated_grid_bytes"] = r.rate.total_bits / 8.0;
  nlohmann::json per_tensor = nlohmann::json::object();
  for (size_t t = 0; t < r.rate.bits.size(); ++t) {
    per_tensor[encoder::RateTensorName(int(t))] = {{"bits", r.rate.bits[t]},
                                                   {"coefficients", r.rate.coeffs[t]}};
  }
  m["estimated_bits_per_tensor"] = per_tensor;
  if (!r.psnr_curve.empty()) {
    nlohmann::json curve = nlohmann::json::array();
    for (const auto& p : r.psnr_curve)
      curve.push_back({{"minutes", p.first}, {"test_psnr", p.second}});
    m["psnr_curve"] = curve;
  }
  return m;
}

// What the file came out as: its size, how it decodes and scores, and the encoder's report.
void AddCodedMetrics(const CodedRun& coded, const trainer::TrainResult& r, size_t float_bytes,
                     nlohmann::json* m) {
  const trainer::EvalResult& d = coded.eval;
  (*m)["test_views"] = d.views;
  (*m)["test_image_size"] = {d.width, d.height};
  // Which pixels the test scores cover: with refined cameras each held-out camera is aligned on
  // its view's left half and the right half is scored (the half-image protocol); else all.
  (*m)["held_out_scoring"] = trainer::HeldOutScoring(d, !r.test_cameras.empty());
  if (coded.as_given.views > 0) {
    // Whole views, unaligned held-out cameras, the file's exposure: the figure of tables that keep
    // the dataset's poses (LLFF's), beside the half-image protocol's.
    (*m)["decoded_test_psnr_as_given"] = coded.as_given.psnr;
    (*m)["decoded_test_ssim_as_given"] = coded.as_given.ssim;
  }
  (*m)["float32_model_bytes"] = float_bytes;
  (*m)["encode_step_scale"] = coded.step_scale;
  (*m)["file_bytes"] = coded.decoded.bytes.size();
  (*m)["decoded_test_psnr"] = d.psnr;
  (*m)["decoded_test_ssim"] = d.ssim;
  (*m)["decode_seconds"] = coded.decoded.decode_seconds;
  (*m)["decoded_render_seconds_per_view"] = d.seconds_per_view;
  (*m)["decoded_samples_per_ray"] = d.samples_per_ray;
  (*m)["decoded_mlp_samples_per_ray"] = d.color_samples_per_ray;  // coloured samples
  (*m)["decoded_work_per_pixel"] = d.work_per_pixel;
  (*m)["head"] = AppearanceName(coded.decoded.info.head, coded.decoded.info.header.hidden);
  (*m)["encode_seconds"] = coded.encode_seconds;
  (*m)["encode"] = EncodeReportJson(coded.report);
  (*m)["coded_to_estimated_grid_bytes"] =
      r.rate.total_bits > 0 ? coded.report.coefficient_bytes() * 8.0 / r.rate.total_bits : 0.0;
}

// What the exposure codes learnt: each training image's gain against the file's exposure.
void AddExposureGains(const trainer::TrainResult& r, const trainer::Dataset& train,
                      nlohmann::json* m) {
  if (r.exposure_log_gain.empty() || r.exposure_log_gain.size() != 3 * train.views.size()) return;
  nlohmann::json gains = nlohmann::json::array();
  for (size_t v = 0; v < train.views.size(); ++v) {
    gains.push_back(
        {{"view", train.views[v].name},
         {"gain",
          {std::exp(r.exposure_log_gain[3 * v]), std::exp(r.exposure_log_gain[3 * v + 1]),
           std::exp(r.exposure_log_gain[3 * v + 2])}}});
  }
  (*m)["exposure_gains"] = gains;
}

// The refined training cameras and the aligned held-out ones, as a camera path that
// `ecrf render --path` takes (views named as in the dataset).
void WriteRefinedCameras(const trainer::TrainResult& r, const trainer::Dataset& train,
                         const trainer::Dataset& test, const std::string& out_dir) {
  if (r.train_cameras.empty()) return;
  std::vector<PathCamera> cameras;
  for (size_t v = 0; v < r.train_cameras.size(); ++v)
    cameras.push_back({train.views[v].name, r.train_cameras[v]});
  for (size_t v = 0; v < r.test_cameras.size(); ++v)
    cameras.push_back({test.views[v].name, r.test_cameras[v]});
  WriteCameraPath(out_dir + "/cameras_refined.json", cameras);
}

// Each camera refinement round's pixel error before and after, and how far the cameras moved
// (the last entry is the held-out views' alignment); the refined intrinsics.
void AddCameraRefinement(const trainer::TrainResult& r, nlohmann::json* m) {
  if (r.camera_refinement.empty()) return;
  nlohmann::json rounds = nlohmann::json::array();
  for (const trainer::CameraRefineStats& s : r.camera_refinement) {
    rounds.push_back({{"mse_before", s.mse_before},
                      {"mse_after", s.mse_after},
                      {"steps", s.steps_taken},
                      {"max_rotation_deg", s.max_rotation_deg},
                      {"max_shift_px", s.max_shift_px}});
  }
  (*m)["camera_refinement"] = rounds;
  const trainer::Camera& c = r.train_cameras.front();
  (*m)["refined_intrinsics"] = {{"fl_x", c.fx}, {"fl_y", c.fy}, {"cx", c.cx}, {"cy", c.cy},
                                {"k1", c.k1},   {"k2", c.k2},   {"p1", c.p1}, {"p2", c.p2},
                                {"w", c.width}, {"h", c.height}};
}

// --save-renders: the decoded file's renders of the scored test views, named by view index.
void SaveRenders(const trainer::TrainOptions& o, const trainer::EvalResult& d) {
  MakeDirectory(o.out_dir + "/renders");
  for (size_t i = 0; i < d.renders.size(); ++i) {
    char name[64];
    std::snprintf(name, sizeof(name), "/renders/test_%03zu.png", i * size_t(o.test_view_stride));
    trainer::SavePng(o.out_dir + name, d.renders[i]);
  }
}

}  // namespace

bool CanResume(const trainer::TrainOptions& o) {
  const std::string path = o.out_dir + "/checkpoint.ckpt";
  if (!FileExists(path)) return false;
  const trainer::CheckpointRunInfo info = trainer::ReadCheckpointRunInfo(path);
  return info.has_config && trainer::ChangedSettings(info.config, o).empty();
}

nlohmann::json TrainEncodeEvaluate(const trainer::TrainOptions& options) {
  CheckRunCanStart(options);
  const OutputDirectory out_dir(options.out_dir);  // before the data: a bad -o fails now
  std::printf("settings: %s\n", DescribeSettings(options).c_str());
  std::fflush(stdout);

  trainer::Dataset train = trainer::LoadTrainingViews(options, "train");
  trainer::Dataset test =
      trainer::DownscaleViews(trainer::LoadTrainingViews(options, "test"), options.eval_downscale);
  trainer::TrainOptions o = options;
  o.test_view_stride = trainer::ScoredTestViewStride(options, test.views.size());
  PrintViews(options, o, train, test);
  WriteRunConfig(options);
  trainer::SceneFit fit = trainer::FitScene(o.scene_type, train);
  PrintSceneFit(fit);
  // Ctrl-C or SIGTERM while training: a checkpoint, then TrainingStopped (stop_signal.h).
  auto stop_on_signal = std::make_unique<trainer::StopSignalScope>();
  const bool warmed_up = trainer::WarmUpCameras(o, fit, &train, &test);
  if (warmed_up) {
    fit = trainer::FitScene(o.scene_type, train);  // on the refined cameras
    PrintSceneFit(fit);
  }
  // A run killed in its warm-up has no checkpoint of its own yet: it starts afresh from the
  // warm-up's cameras, as the uninterrupted run did.
  o.resume = options.resume && FileExists(options.out_dir + "/checkpoint.ckpt");
  trainer::TensorfModel model(trainer::ConfigFor(o, train, fit));
  trainer::RateState rate;
  const trainer::TrainResult r = trainer::Train(o, train, test, &model, &rate);
  stop_on_signal.reset();  // encoding and scoring stop at Ctrl-C as any program does

  size_t float_bytes = 0;
  for (const auto& a : model.NamedParameters()) float_bytes += a.size * sizeof(float);
  CodedRun coded;
  EncodeDecodeEvaluate(o, model, rate, r, test, &coded);
  PrintRunSummary(o, r, float_bytes, coded);

  nlohmann::json m = TrainingMetrics(o, r, model, fit, train, warmed_up);
  AddCodedMetrics(coded, r, float_bytes, &m);
  AddExposureGains(r, train, &m);
  WriteRefinedCameras(r, train, test, o.out_dir);
  AddCameraRefinement(r, &m);
  const std::string text = m.dump(2) + "\n";
  trainer::WriteFileAtomically(o.out_dir + "/metrics.json", text.data(), text.size());
  if (o.save_renders) SaveRenders(o, coded.eval);
  return m;
}

}  // namespace tools
}  // namespace ecrf
