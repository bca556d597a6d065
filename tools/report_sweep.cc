// `ecrf report sweep`: one training run per lambda_e, each encoded, decoded and scored, then the
// rate–distortion report. Finished runs in REPORT/runs/ are reused, so an interrupted sweep
// resumes where it stopped, and the report is rewritten after every point.
#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "ecrf/decoder.h"
#include "tools/cli_args.h"
#include "tools/report.h"
#include "tools/report_speed.h"
#include "tools/train_run.h"
#include "trainer/checkpoint.h"

namespace ecrf {
namespace tools {
namespace {

const char kSweepUsage[] =
    "usage: ecrf report sweep (--data DIR | --scene builtin) --lambdas L1,L2,... -o REPORT_DIR [options]\n"
    "  --anchors FILE.json        reference points drawn on the plots (docs/reports/anchors_paper.json)\n"
    "  --render                   also run the speed-error sweep (as `ecrf report render`)\n"
    "  --test-stride K            score every K-th test view (default 10; 1 for the built-in scene)\n"
    "  --eval-every N             training-curve interval (default iters/4)\n"
    "every `ecrf train` option applies to each run:\n";

std::string SceneName(const trainer::TrainOptions& o) {
  if (o.builtin_scene) return "builtin";
  std::string d = o.data_dir;
  while (d.size() > 1 && d.back() == '/') d.pop_back();
  const size_t slash = d.find_last_of('/');
  return slash == std::string::npos ? d : d.substr(slash + 1);
}

std::vector<double> ParseLambdas(const std::string& text) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const double v = ParseFloat("--lambdas", item.c_str());
    bool seen = false;
    for (double w : out) seen |= LambdaText(w) == LambdaText(v);
    if (!seen) out.push_back(v);
  }
  if (out.empty()) throw std::invalid_argument("--lambdas: no values (e.g. --lambdas 0,1e-10,5e-10)");
  return out;
}

std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, 10, "model name") == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  }
  return "unknown";
}

std::string Today() {
  const std::time_t now = std::time(nullptr);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%d", std::gmtime(&now));
  return text;
}

// A finished run is reused only when it was trained as this sweep would train it.
void CheckReusable(const nlohmann::json& m, const trainer::TrainOptions& o, const std::string& path) {
  auto mismatch = [&](const std::string& what, const std::string& had, const std::string& want) {
    throw std::runtime_error(path + ": finished run has " + what + " " + had + ", this sweep asks for " + want +
                             "; remove that run directory or report into another -o");
  };
  const std::string data = o.builtin_scene ? "builtin" : o.data_dir;
  if (m.value("preset", "") != o.preset) mismatch("preset", m.value("preset", "?"), o.preset);
  if (m.value("data", "") != data) mismatch("data", m.value("data", "?"), data);
  if (m.value("iterations", -1) != o.iters) {
    mismatch("iterations", std::to_string(m.value("iterations", -1)), std::to_string(o.iters));
  }
  if (m.contains("test_view_stride") && m["test_view_stride"] != o.test_view_stride) {
    mismatch("test stride", m["test_view_stride"].dump(), std::to_string(o.test_view_stride));
  }
  if (m.contains("seed") && m["seed"] != o.seed) mismatch("seed", m["seed"].dump(), std::to_string(o.seed));
  // Runs from before these options existed were trained with their defaults (1 and off).
  auto check_float = [&](const char* key, const char* what, float want) {
    const double had = m.value(key, 1.0);
    if (std::fabs(had - want) > 1e-6 * std::fabs(want)) mismatch(what, std::to_string(had), std::to_string(want));
  };
  check_float("quant_step_scale", "quantization step scale", o.quant_step_scale);
  check_float("qat_start", "quantization-aware start", o.qat_start);
  if (m.value("mlp_levels", 0) != o.mlp_levels) {
    mismatch("MLP levels", std::to_string(m.value("mlp_levels", 0)), std::to_string(o.mlp_levels));
  }
}

std::string Minutes(double seconds) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f min", seconds / 60.0);
  return text;
}

}  // namespace

int RunReportSweep(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
      std::printf("%s%s", kSweepUsage, kTrainFlagsUsage);
      return 0;
    }
  }
  std::vector<int> rest;
  trainer::TrainOptions o = TrainOptionsFromArgs(argc, argv, &rest);
  std::string out, lambdas_text, anchors_path;
  bool render = false, stride_given = false, eval_given = false;
  for (int i = 1; i < argc; ++i) {
    stride_given |= !std::strcmp(argv[i], "--test-stride");
    eval_given |= !std::strcmp(argv[i], "--eval-every");
  }
  for (size_t k = 0; k < rest.size(); ++k) {
    const std::string a = argv[rest[k]];
    auto value = [&]() -> std::string {
      if (k + 1 >= rest.size() || rest[k + 1] != rest[k] + 1) throw std::invalid_argument(a + " needs a value");
      return argv[rest[++k]];
    };
    if (a == "-o" || a == "--out") {
      out = value();
    } else if (a == "--lambdas") {
      lambdas_text = value();
    } else if (a == "--anchors") {
      anchors_path = value();
    } else if (a == "--render") {
      render = true;
    } else {
      std::fprintf(stderr, "ecrf report sweep: unknown option '%s'\n\n%s%s", a.c_str(), kSweepUsage,
                   kTrainFlagsUsage);
      return 2;
    }
  }
  if (out.empty() || lambdas_text.empty() || (!o.builtin_scene && o.data_dir.empty())) {
    std::fprintf(stderr, "ecrf report sweep: needs --data DIR or --scene builtin, --lambdas and -o\n\n%s%s",
                 kSweepUsage, kTrainFlagsUsage);
    return 2;
  }
  const std::vector<double> lambdas = ParseLambdas(lambdas_text);
  if (!stride_given) o.test_view_stride = o.builtin_scene ? 1 : 10;
  if (!eval_given) o.eval_every = std::max(1, o.iters / 4);
  nlohmann::json anchors = nlohmann::json::array();
  if (!anchors_path.empty()) {
    const nlohmann::json a = ReadJsonFile(anchors_path);
    if (!a.contains("anchors") || !a["anchors"].is_array()) {
      throw std::runtime_error(anchors_path + ": expected {\"anchors\": [{\"label\": ..., ...}]}");
    }
    anchors = a["anchors"];
  }
  // Find an unusable output directory now, not after the first hour of training.
  MakeDirectory(out + "/runs");
  WriteTextFile(out + "/.write_probe", "");
  std::remove((out + "/.write_probe").c_str());

  nlohmann::json report;
  if (FileExists(out + "/report.json")) {
    report = ReadReport(out);  // keeps an earlier speed section
  }
  report["scene"] = SceneName(o);
  report["data"] = o.builtin_scene ? "builtin" : o.data_dir;
  report["sweep"] = {{"preset", o.preset},          {"iterations", o.iters},
                     {"lambdas", lambdas},          {"alpha", o.alpha},
                     {"test_view_stride", o.test_view_stride}, {"max_test_views", o.max_test_views},
                     {"eval_every", o.eval_every},  {"seed", o.seed},
                     {"downscale", o.downscale},    {"threads", omp_get_max_threads()}};
  report["machine"] = {{"cpu", CpuModel()}, {"hardware_threads", std::thread::hardware_concurrency()}};
  report["ecrf_version"] = ecrf_version_string();
  report["bitstream_version"] = ecrf_bitstream_version();
  report["date"] = Today();
  report["anchors"] = anchors;
  report["points"] = nlohmann::json::array();

  double trained_seconds = 0.0;
  int trained = 0;
  for (size_t k = 0; k < lambdas.size(); ++k) {
    const std::string name = LambdaText(lambdas[k]);
    const std::string run_dir = out + "/runs/" + name;
    const std::string metrics_path = run_dir + "/metrics.json";
    nlohmann::json metrics;
    if (FileExists(metrics_path)) {
      metrics = ReadJsonFile(metrics_path);
      CheckReusable(metrics, o, metrics_path);
      std::fprintf(stderr, "report: point %zu/%zu (lambda_e %g): reusing the finished run in %s\n", k + 1,
                   lambdas.size(), lambdas[k], run_dir.c_str());
    } else {
      size_t left = 0;
      for (size_t j = k; j < lambdas.size(); ++j) left += !FileExists(out + "/runs/" + LambdaText(lambdas[j]) + "/metrics.json");
      const std::string eta = trained ? "sweep ETA " + Minutes(trained_seconds / trained * left)
                                      : "sweep ETA known after the first point";
      std::fprintf(stderr, "report: point %zu/%zu (lambda_e %g): training into %s; %zu to train, %s\n", k + 1,
                   lambdas.size(), lambdas[k], run_dir.c_str(), left, eta.c_str());
      trainer::TrainOptions run = o;
      run.out_dir = run_dir;
      run.lambda_e = float(lambdas[k]);
      const auto start = std::chrono::steady_clock::now();
      metrics = TrainEncodeEvaluate(run);
      trained_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      ++trained;
    }
    report["points"].push_back(RatePointFromMetrics(metrics, "runs/" + name));
    AddReferenceColumns(&report);
    WriteReport(out, report);
  }
  if (render) RunSpeedSweep(out, SpeedSweepOptions(), &report);
  std::printf("%-14s %10s %8s %10s %10s %9s %10s\n", "point", "bytes", "ratio", "decoded", "float", "loss",
              "train");
  for (const nlohmann::json& p : report["points"]) {
    const double loss = p["psnr_loss_db"].is_null() ? NAN : p["psnr_loss_db"].get<double>();
    std::printf("%-14s %10lld %7.1fx %7.2f dB %7.2f dB %+6.2f dB %10s\n", p["label"].get<std::string>().c_str(),
                p["file_bytes"].get<long long>(), p["ratio"].get<double>(), p["decoded_psnr"].get<double>(),
                p["float_psnr"].get<double>(), loss, Minutes(p["train_seconds"].get<double>()).c_str());
  }
  std::printf("report: %s/index.html (report.json, CSV files and plots beside it)\n", out.c_str());
  return 0;
}

}  // namespace tools
}  // namespace ecrf
