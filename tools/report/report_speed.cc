#include "tools/report/report_speed.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include "tools/cli.h"
#include "tools/decoded_scene.h"
#include "tools/report/report.h"
#include "trainer/data/file_io.h"
#include "trainer/train/checkpoint.h"

namespace ecrf {
namespace tools {
namespace {

// A field of /proc/self/status in kB (-1 where there is no such file: not Linux).
long ProcStatusKb(const char* field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const size_t n = std::strlen(field);
  while (std::getline(in, line)) {
    if (line.compare(0, n, field) == 0) return std::atol(line.c_str() + n);
  }
  return -1;
}

// Sets the peak RSS back to the current RSS (Linux >= 4.0), so that the peak measured next is
// the decoder's and not the training run's that may have preceded it in this process.
bool ResetPeakRss() {
  FILE* f = std::fopen("/proc/self/clear_refs", "w");
  if (!f) return false;
  const bool ok = std::fputs("5", f) >= 0;
  return std::fclose(f) == 0 && ok;
}

// One setting of the renderer: a knob moved away from the defaults.
struct Setting {
  std::string knob, value;
  dec::RenderOptions options;
  bool int16 = false;
  int image_scale = 1;
  bool is_default = false;
};

std::vector<Setting> Settings(int all_threads, float scene_threshold) {
  dec::RenderOptions base;
  base.num_threads = 0;
  std::vector<Setting> s;
  auto add = [&](const std::string& knob, const std::string& value, auto change) {
    Setting x;
    x.knob = knob;
    x.value = value;
    x.options = base;
    change(x);
    s.push_back(x);
  };
  char text[32];
  add("default", "default", [](Setting& x) { x.is_default = true; });
  add("threads", "1", [](Setting& x) { x.options.num_threads = 1; });
  std::snprintf(text, sizeof(text), "all (%d)", all_threads);
  add("threads", text, [](Setting& x) { x.is_default = true; });
  add("grid_storage", "float32", [](Setting& x) { x.is_default = true; });
  add("grid_storage", "int16", [](Setting& x) { x.int16 = true; });
  add("skip_empty_space", "off", [](Setting& x) { x.options.skip_empty_space = false; });
  add("skip_empty_space", "on", [](Setting& x) { x.is_default = true; });
  add("early_stop", "0", [](Setting& x) { x.options.early_stop_transmittance = 0.f; });
  add("early_stop", "1e-4", [](Setting& x) { x.is_default = true; });
  for (float t : {1e-3f, 1e-2f, 3e-2f}) {
    std::snprintf(text, sizeof(text), "%g", double(t));
    add("early_stop", text, [t](Setting& x) { x.options.early_stop_transmittance = t; });
  }
  std::snprintf(text, sizeof(text), "%g", double(scene_threshold));
  add("weight_threshold", text, [](Setting& x) { x.is_default = true; });
  for (float w : {1e-3f, 1e-2f, 3e-2f, 1e-1f}) {
    if (w <= scene_threshold) continue;
    std::snprintf(text, sizeof(text), "%g", double(w));
    add("weight_threshold", text, [w](Setting& x) { x.options.weight_threshold = w; });
  }
  for (float k : {0.5f, 1.f, 1.5f, 2.f, 3.f, 4.f}) {
    std::snprintf(text, sizeof(text), "%g", double(k));
    if (k == 1.f) {
      add("step_scale", text, [](Setting& x) { x.is_default = true; });
    } else {
      add("step_scale", text, [k](Setting& x) { x.options.step_scale = k; });
    }
  }
  add("image_scale", "1", [](Setting& x) { x.is_default = true; });
  add("image_scale", "1/2", [](Setting& x) { x.image_scale = 2; });
  add("image_scale", "1/4", [](Setting& x) { x.image_scale = 4; });
  return s;
}

const nlohmann::json& ChoosePoint(const nlohmann::json& report, double lambda) {
  const nlohmann::json& points = report.at("points");
  if (points.empty())
    throw std::runtime_error("the report has no rate points yet (run `ecrf report sweep`)");
  if (lambda < 0) return points[points.size() / 2];
  for (const nlohmann::json& p : points) {
    if (LambdaText(p.at("lambda_e").get<double>()) == LambdaText(lambda)) return p;
  }
  throw std::runtime_error("the report has no point with lambda_e " + std::to_string(lambda));
}

// Decodes `reps` times and keeps the fastest (the first also warms the caches).
LoadedScene TimedDecode(const std::vector<uint8_t>& bytes, const std::string& name,
                        dec::GridStorage storage, int reps, double* best_seconds) {
  LoadedScene s;
  *best_seconds = 1e30;
  for (int r = 0; r < reps; ++r) {
    s = LoadedScene();  // free the previous grids first: the peak RSS is one decode's
    s = DecodeSceneBytes(bytes, name, storage);
    *best_seconds = std::min(*best_seconds, s.decode_seconds);
  }
  return s;
}

}  // namespace

void RunSpeedSweep(const std::string& dir, const SpeedSweepOptions& so, nlohmann::json* report) {
  const nlohmann::json point = ChoosePoint(*report, so.lambda);
  const std::string file = dir + "/" + point.at("run_dir").get<std::string>() + "/scene.ecrf";
  const int sweep_stride = report->at("sweep").value("test_view_stride", 1);
  const int stride = so.stride > 0 ? so.stride : 2 * sweep_stride;
  const int max_views =
      so.max_views > 0 ? so.max_views : report->at("sweep").value("max_test_views", 0);

  // Decode first, so that the growth of the peak RSS is the decoder's.
  const std::vector<uint8_t> bytes = trainer::ReadWholeFile(file);
  const bool reset = ResetPeakRss();
  const long rss_before = ProcStatusKb("VmRSS:");
  double f32_seconds = 0.0, i16_seconds = 0.0;
  const LoadedScene f32 = TimedDecode(bytes, file, dec::GridStorage::kFloat32, 3, &f32_seconds);
  const long rss_peak = ProcStatusKb("VmHWM:");
  const LoadedScene i16 = TimedDecode(bytes, file, dec::GridStorage::kInt16, 3, &i16_seconds);

  const std::string data = report->at("data").get<std::string>();
  const trainer::Dataset test =
      IsProceduralScene(data)
          ? ProceduralDataset(data, "test",
                              report->at("sweep").value("seed", trainer::TrainOptions().seed))
          : trainer::LoadDataset(data, "test", report->at("sweep").value("downscale", 1));
  const unsigned hw = std::thread::hardware_concurrency();
  const int all_threads = hw == 0 ? 1 : int(std::min<unsigned>(hw, dec::kMaxRenderThreads));
  const std::vector<Setting> settings = Settings(all_threads, f32.field->weight_threshold);

  std::fprintf(stderr, "report: speed-error sweep of %s: %zu settings, test views with stride %d\n",
               file.c_str(), settings.size(), stride);
  // One untimed view first: page faults and cold caches belong to no setting.
  EvaluateDecoded(*f32.field, test, stride, 1, dec::RenderOptions(), false);
  nlohmann::json rows = nlohmann::json::array();
  nlohmann::json measured_default;
  for (const Setting& s : settings) {
    if (s.is_default && !measured_default.is_null()) {
      nlohmann::json row = measured_default;
      row["knob"] = s.knob;
      row["setting"] = s.value;
      rows.push_back(row);
      continue;
    }
    dec::RenderStats stats;
    const trainer::EvalResult r =
        EvaluateDecoded(s.int16 ? *i16.field : *f32.field, test, stride, max_views, s.options,
                        false, s.image_scale, &stats);
    const double rays = std::max<double>(1.0, double(stats.rays));
    const int threads = s.options.num_threads == 0 ? all_threads : s.options.num_threads;
    nlohmann::json row = {{"knob", s.knob},
                          {"setting", s.value},
                          {"is_default", s.is_default},
                          {"seconds_per_view", r.seconds_per_view},
                          {"psnr", r.psnr},
                          {"ssim", r.ssim},
                          {"views", r.views},
                          {"threads", threads},
                          {"width", test.views[0].camera.width / s.image_scale},
                          {"height", test.views[0].camera.height / s.image_scale},
                          {"samples_per_ray", double(stats.samples) / rays},
                          {"mlp_samples_per_ray", double(stats.color_samples) / rays}};
    std::fprintf(stderr,
                 "  %-17s %-9s %8.1f ms/view  %6.2f dB  %7.1f samples/ray  %6.2f MLP samples/ray\n",
                 s.knob.c_str(), s.value.c_str(), 1e3 * r.seconds_per_view, r.psnr,
                 double(stats.samples) / rays, double(stats.color_samples) / rays);
    if (s.is_default) measured_default = row;
    rows.push_back(row);
  }
  const double mb = double(bytes.size()) / 1e6;
  nlohmann::json speed;
  speed["point"] = point.at("label");
  speed["file"] = point.at("run_dir").get<std::string>() + "/scene.ecrf";
  speed["file_bytes"] = bytes.size();
  speed["test_view_stride"] = stride;
  speed["views"] = measured_default.value("views", 0);
  speed["scene_weight_threshold"] = f32.field->weight_threshold;
  speed["decode"] = {
      {"float32_seconds", f32_seconds},
      {"int16_seconds", i16_seconds},
      {"float32_ms_per_mb", 1e3 * f32_seconds / mb},
      {"int16_ms_per_mb", 1e3 * i16_seconds / mb},
      {"float32_grid_bytes",
       f32.field->density.StorageBytes() + f32.field->appearance.StorageBytes()},
      {"int16_grid_bytes",
       i16.field->density.StorageBytes() + i16.field->appearance.StorageBytes()},
      {"peak_rss_growth_bytes", reset && rss_before >= 0 && rss_peak >= 0
                                    ? nlohmann::json((rss_peak - rss_before) * 1024.0)
                                    : nlohmann::json()}};
  speed["rows"] = rows;
  (*report)["speed"] = speed;
  WriteReport(dir, *report);
}

int RunReportRender(int argc, char** argv) {
  std::string dir;
  SpeedSweepOptions so;
  auto app = MakeCommand(
      "report render",
      "the speed-error sweep of the renderer on one rate point of a report: decode time and "
      "memory, then the render time per view and the PSNR of the decoded file for each speed "
      "knob (SPEC.md 7.8), one knob at a time from the defaults");
  app->add_option("REPORT", dir, "the report directory (from ecrf report sweep)")
      ->type_name("DIR")
      ->required();
  app->add_option("--lambda", so.lambda, "the rate point to measure (its lambda_e)")
      ->type_name("X")
      ->check(CLI::NonNegativeNumber)
      ->default_str("the middle point of the sweep");
  app->add_option("--test-stride", so.stride, "every K-th test view")
      ->type_name("K")
      ->check(CLI::Range(1, 1000000))
      ->default_str("twice the sweep's test stride");
  app->add_option("--max-test-views", so.max_views,
                  "at most N views per setting (0 = the sweep's --max-test-views)")
      ->type_name("N")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  AddRenamedFlag(app.get(), "--stride", "--test-stride");
  AddRenamedFlag(app.get(), "--max-views", "--max-test-views");  // as train and eval call it
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  nlohmann::json report = ReadReport(dir);
  RunSpeedSweep(dir, so, &report);
  std::printf("report: %s/index.html (speed-error section)\n", dir.c_str());
  return 0;
}

}  // namespace tools
}  // namespace ecrf
