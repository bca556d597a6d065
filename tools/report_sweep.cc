// `ecrf report sweep`: one training run per lambda_e, each encoded, decoded and scored, then the
// rate–distortion report. Finished runs in REPORT/runs/ are reused, so an interrupted sweep
// resumes where it stopped, and the report is rewritten after every point.
#include <omp.h>

#include <climits>
#include <cstdlib>
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
    "usage: ecrf report sweep (--data DIR | --scene builtin|capture|forward) --lambdas L1,L2,... -o REPORT_DIR [options]\n"
    "  --lambdas L1,L2@S,...      one run per lambda_e; L@S trains that point with steps x S\n"
    "                             (S overrides --quant-step-scale for it; e.g. 0,2e-11@3,5e-10)\n"
    "  --anchors FILE.json        reference points drawn on the plots (docs/reports/anchors_paper.json)\n"
    "  --render                   also run the speed-error sweep (as `ecrf report render`)\n"
    "  --reference REPORT_DIR     without a lambda 0 point: take the lambda = 0 float32 reference of\n"
    "                             that earlier sweep (same data, preset, iterations, seed, stride)\n"
    "  --test-stride K            score every K-th test view (default 10; 1 for the built-in scene)\n"
    "  --eval-every N             training-curve interval (default iters/4)\n"
    "every `ecrf train` option applies to each run:\n";

std::string SceneName(const trainer::TrainOptions& o) {
  if (!o.procedural_scene.empty()) return o.procedural_scene;
  std::string d = o.data_dir;
  while (d.size() > 1 && d.back() == '/') d.pop_back();
  const size_t slash = d.find_last_of('/');
  return slash == std::string::npos ? d : d.substr(slash + 1);
}

struct SweepPoint {
  double lambda;
  float step_scale;
};

// "0,2e-11@3,1e-10": lambda_e values, each with an optional step scale after '@'.
std::vector<SweepPoint> ParsePoints(const std::string& text, float default_step_scale) {
  std::vector<SweepPoint> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    SweepPoint p{0.0, default_step_scale};
    const size_t at = item.find('@');
    p.lambda = ParseFloat("--lambdas", item.substr(0, at).c_str());
    if (at != std::string::npos) {
      p.step_scale = ParseFloat("--lambdas (step scale after @)", item.substr(at + 1).c_str());
      if (!(p.step_scale > 0.f)) throw std::invalid_argument("--lambdas: the step scale after @ must be > 0 in '" + item + "'");
    }
    bool seen = false;
    for (const SweepPoint& q : out) seen |= LambdaText(q.lambda, q.step_scale) == LambdaText(p.lambda, p.step_scale);
    if (!seen) out.push_back(p);
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

// "../shared/data/chair" and "/work/shared/data/chair" are the same data (relative paths as seen
// from the current directory).
bool SameData(const std::string& a, const std::string& b) {
  if (a == b) return true;
  char ra[PATH_MAX], rb[PATH_MAX];
  return realpath(a.c_str(), ra) && realpath(b.c_str(), rb) && std::strcmp(ra, rb) == 0;
}

// A finished run is reused only when it was trained as this sweep would train it.
void CheckReusable(const nlohmann::json& m, const trainer::TrainOptions& o, const std::string& path) {
  auto mismatch = [&](const std::string& what, const std::string& had, const std::string& want) {
    throw std::runtime_error(path + ": finished run has " + what + " " + had + ", this sweep asks for " + want +
                             "; remove that run directory or report into another -o");
  };
  const std::string& data = trainer::DataSource(o);
  if (m.value("preset", "") != o.preset) mismatch("preset", m.value("preset", "?"), o.preset);
  if (!SameData(m.value("data", ""), data)) mismatch("data", m.value("data", "?"), data);
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

// The lambda = 0 float model of an earlier sweep, usable when this sweep trains it the same way.
nlohmann::json BorrowReference(const std::string& dir, const nlohmann::json& sweep, const std::string& data) {
  const nlohmann::json other = ReadReport(dir);
  if (!other.contains("reference") || other["reference"].is_null()) {
    throw std::runtime_error(dir + "/report.json: has no lambda = 0 reference to borrow");
  }
  if (!SameData(other.value("data", ""), data)) {
    throw std::runtime_error(dir + "/report.json: reference of data " + other.value("data", "?") + ", this sweep is of " + data);
  }
  for (const char* key : {"preset", "iterations", "seed", "test_view_stride", "max_test_views", "downscale"}) {
    if (!other.contains("sweep") || other["sweep"].value(key, nlohmann::json()) != sweep.at(key)) {
      throw std::runtime_error(dir + "/report.json: its sweep has " + key + " " +
                               (other.contains("sweep") ? other["sweep"].value(key, nlohmann::json()).dump() : "?") +
                               ", this one " + sweep.at(key).dump() + "; its reference does not apply");
    }
  }
  nlohmann::json ref = other["reference"];
  ref["label"] = "lambda=0 float32 model (from " + dir + ")";
  return ref;
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
  std::string out, lambdas_text, anchors_path, reference_dir;
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
    } else if (a == "--reference") {
      reference_dir = value();
    } else if (a == "--render") {
      render = true;
    } else {
      std::fprintf(stderr, "ecrf report sweep: unknown option '%s'\n\n%s%s", a.c_str(), kSweepUsage,
                   kTrainFlagsUsage);
      return 2;
    }
  }
  if (out.empty() || lambdas_text.empty() || trainer::DataSource(o).empty()) {
    std::fprintf(stderr, "ecrf report sweep: needs --data DIR or --scene builtin|capture|forward, --lambdas and -o\n\n%s%s",
                 kSweepUsage, kTrainFlagsUsage);
    return 2;
  }
  const std::vector<SweepPoint> points = ParsePoints(lambdas_text, o.quant_step_scale);
  std::vector<double> lambdas, step_scales;
  for (const SweepPoint& p : points) {
    lambdas.push_back(p.lambda);
    step_scales.push_back(p.step_scale);
  }
  if (!stride_given) o.test_view_stride = o.procedural_scene.empty() ? 10 : 1;
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
  const OutputDirectory runs_dir(out + "/runs");

  nlohmann::json report;
  if (FileExists(out + "/report.json")) {
    report = ReadReport(out);  // keeps an earlier speed section
  }
  report["scene"] = SceneName(o);
  report["data"] = trainer::DataSource(o);
  report["sweep"] = {{"preset", o.preset},          {"iterations", o.iters},
                     {"lambdas", lambdas},          {"step_scales", step_scales}, {"alpha", o.alpha},
                     {"test_view_stride", o.test_view_stride}, {"max_test_views", o.max_test_views},
                     {"eval_every", o.eval_every},  {"seed", o.seed},
                     {"downscale", o.downscale},    {"threads", omp_get_max_threads()}};
  report["machine"] = {{"cpu", CpuModel()}, {"hardware_threads", std::thread::hardware_concurrency()}};
  report["ecrf_version"] = ecrf_version_string();
  report["bitstream_version"] = ecrf_bitstream_version();
  report["date"] = Today();
  report["anchors"] = anchors;
  report.erase("borrowed_reference");
  if (!reference_dir.empty()) {
    report["borrowed_reference"] = BorrowReference(reference_dir, report["sweep"], report["data"].get<std::string>());
  }
  report["points"] = nlohmann::json::array();

  double trained_seconds = 0.0;
  int trained = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    trainer::TrainOptions run = o;
    run.lambda_e = float(points[k].lambda);
    run.quant_step_scale = points[k].step_scale;
    const std::string name = LambdaText(points[k].lambda, points[k].step_scale);
    const std::string run_dir = out + "/runs/" + name;
    const std::string metrics_path = run_dir + "/metrics.json";
    nlohmann::json metrics;
    if (FileExists(metrics_path)) {
      metrics = ReadJsonFile(metrics_path);
      CheckReusable(metrics, run, metrics_path);
      std::fprintf(stderr, "report: point %zu/%zu (lambda_e %g): reusing the finished run in %s\n", k + 1,
                   points.size(), points[k].lambda, run_dir.c_str());
    } else {
      size_t left = 0;
      for (size_t j = k; j < points.size(); ++j) {
        left += !FileExists(out + "/runs/" + LambdaText(points[j].lambda, points[j].step_scale) + "/metrics.json");
      }
      const std::string eta = trained ? "sweep ETA " + Minutes(trained_seconds / trained * left)
                                      : "sweep ETA known after the first point";
      std::fprintf(stderr, "report: point %zu/%zu (lambda_e %g): training into %s; %zu to train, %s\n", k + 1,
                   points.size(), points[k].lambda, run_dir.c_str(), left, eta.c_str());
      run.out_dir = run_dir;
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
  std::printf("%-24s %10s %8s %10s %10s %9s %10s\n", "point", "bytes", "ratio", "decoded", "float", "loss",
              "train");
  for (const nlohmann::json& p : report["points"]) {
    const double loss = p["psnr_loss_db"].is_null() ? NAN : p["psnr_loss_db"].get<double>();
    std::printf("%-24s %10lld %7.1fx %7.2f dB %7.2f dB %+6.2f dB %10s\n", p["label"].get<std::string>().c_str(),
                p["file_bytes"].get<long long>(), p["ratio"].get<double>(), p["decoded_psnr"].get<double>(),
                p["float_psnr"].get<double>(), loss, Minutes(p["train_seconds"].get<double>()).c_str());
  }
  std::printf("report: %s/index.html (report.json, CSV files and plots beside it)\n", out.c_str());
  return 0;
}

}  // namespace tools
}  // namespace ecrf
