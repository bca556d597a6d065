// `ecrf report sweep`: one training run per lambda_e, each encoded, decoded and scored, then the
// rate–distortion report. Finished runs in REPORT/runs/ are reused, so an interrupted sweep
// resumes where it stopped, and the report is rewritten after every point. With --plan the points
// become a plan of independent tasks for Slurm or GNU parallel (sweep_plan.h), and --collect
// reports what those tasks finished without training anything.
#include <omp.h>

#include <unistd.h>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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
#include "tools/report/report.h"
#include "tools/report/report_speed.h"
#include "tools/report/sweep_plan.h"
#include "tools/train_flags.h"
#include "tools/train_run.h"
#include "trainer/data/seconds_since.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/train_config.h"
#include "trainer/train/train_options.h"

namespace ecrf {
namespace tools {
namespace {

std::string SceneName(const trainer::TrainOptions& o) {
  if (o.procedural_scene != trainer::ProceduralScene::kNone)
    return trainer::NameOf(o.procedural_scene);
  std::string d = o.data_dir;
  while (d.size() > 1 && d.back() == '/') d.pop_back();
  const size_t slash = d.find_last_of('/');
  return slash == std::string::npos ? d : d.substr(slash + 1);
}

// One run of the sweep: a named rate point (--rate R), a file size (--target-size SIZE) or a
// lambda_e on the sweep's base (--lambda-e X, with --quant-step-scale S for "X@S"), resolved like
// the same `ecrf train` command line.
struct SweepPoint {
  std::string rate;    // "" for a lambda or size point
  std::string target;  // "" for a lambda or rate point
  double lambda = 0.0;
  float step_scale = 0.0f;  // 0: the base's
};

std::vector<std::string> PointArgs(const SweepPoint& p) {
  if (!p.rate.empty()) return {"--rate", p.rate};
  if (!p.target.empty()) return {"--target-size", p.target};
  char text[32];
  std::snprintf(text, sizeof(text), "%.9g", p.lambda);
  std::vector<std::string> args = {"--lambda-e", text};
  if (p.step_scale > 0.f) {
    std::snprintf(text, sizeof(text), "%.9g", double(p.step_scale));
    args.insert(args.end(), {"--quant-step-scale", text});
  }
  return args;
}

std::string PointName(const SweepPoint& p, const trainer::TrainOptions& resolved) {
  if (!p.target.empty()) return "target_" + p.target;
  return p.rate.empty() ? LambdaText(p.lambda, resolved.quant_step_scale) : "rate_" + p.rate;
}

// The items of a comma-separated list, as --rates, --targets and --lambdas give them.
std::vector<std::string> CommaItems(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) items.push_back(item);
  return items;
}

// "316KB,127KB": file sizes, one --target-size run each. The text names the run directory, so it
// is kept to letters, digits and '.'; `ecrf train` parses and checks the size itself.
std::vector<SweepPoint> ParseTargets(const std::string& text) {
  std::vector<SweepPoint> out;
  for (const std::string& item : CommaItems(text)) {
    const bool plain = !item.empty() && std::all_of(item.begin(), item.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '.';
    });
    if (!plain) throw std::invalid_argument("--targets: '" + item + "' is not a size like 316KB");
    SweepPoint p;
    p.target = item;
    out.push_back(p);
  }
  return out;
}

// "low,medium,high": named rate points.
std::vector<SweepPoint> ParseRates(const std::string& text) {
  std::vector<SweepPoint> out;
  for (const std::string& item : CommaItems(text)) {
    trainer::TrainOptions check;
    trainer::ApplyRatePoint(item, &check);  // throws for unknown names
    SweepPoint p;
    p.rate = item;
    out.push_back(p);
  }
  return out;
}

// "0,2e-11@3,1e-10": lambda_e values, each with an optional step scale after '@'.
std::vector<SweepPoint> ParsePoints(const std::string& text) {
  std::vector<SweepPoint> out;
  for (const std::string& item : CommaItems(text)) {
    SweepPoint p;
    const size_t at = item.find('@');
    p.lambda = ParseFloat("--lambdas", item.substr(0, at).c_str());
    if (at != std::string::npos) {
      p.step_scale = ParseFloat("--lambdas (step scale after @)", item.substr(at + 1).c_str());
      if (!(p.step_scale > 0.f))
        throw std::invalid_argument("--lambdas: the step scale after @ must be > 0 in '" + item +
                                    "'");
    }
    bool seen = false;
    for (const SweepPoint& q : out) seen |= q.lambda == p.lambda && q.step_scale == p.step_scale;
    if (!seen) out.push_back(p);
  }
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

// A finished run is reused only when it was trained as this sweep would train it: by its
// config.json when it has one (every setting), else by the metrics older runs recorded.
void CheckReusable(const nlohmann::json& m, const trainer::TrainOptions& o,
                   const std::string& path) {
  const std::string dir = path.substr(0, path.find_last_of('/'));
  if (FileExists(dir + "/config.json")) {
    const trainer::TrainOptions had = trainer::TrainConfigFromJson(
        ReadJsonFile(dir + "/config.json").dump(), dir + "/config.json");
    std::vector<std::string> changed = trainer::ChangedSettings(had, o);
    // The same data under another relative path is the same run.
    changed.erase(std::remove_if(changed.begin(), changed.end(),
                                 [&](const std::string& c) {
                                   return c.rfind("data_dir:", 0) == 0 &&
                                          SameData(had.data_dir, o.data_dir);
                                 }),
                  changed.end());
    if (changed.empty()) return;
    std::string list;
    for (const std::string& c : changed) list += "\n  " + c;
    throw std::runtime_error(dir + ": finished run has other settings than this sweep asks for:" +
                             list + "\nremove that run directory or report into another -o");
  }
  auto mismatch = [&](const std::string& what, const std::string& had, const std::string& want) {
    throw std::runtime_error(path + ": finished run has " + what + " " + had +
                             ", this sweep asks for " + want +
                             "; remove that run directory or report into another -o");
  };
  const std::string& data = trainer::DataSource(o);
  if (m.value("preset", "") != trainer::NameOf(o.preset))
    mismatch("preset", m.value("preset", "?"), trainer::NameOf(o.preset));
  if (!SameData(m.value("data", ""), data)) mismatch("data", m.value("data", "?"), data);
  if (m.value("iterations", -1) != o.iters) {
    mismatch("iterations", std::to_string(m.value("iterations", -1)), std::to_string(o.iters));
  }
  if (m.contains("test_view_stride") && m["test_view_stride"] != o.test_view_stride) {
    mismatch("test stride", m["test_view_stride"].dump(), std::to_string(o.test_view_stride));
  }
  if (m.contains("seed") && m["seed"] != o.seed)
    mismatch("seed", m["seed"].dump(), std::to_string(o.seed));
  // Runs from before these options existed were trained with their defaults (1 and off).
  auto check_float = [&](const char* key, const char* what, float want) {
    const double had = m.value(key, 1.0);
    if (std::fabs(had - want) > 1e-6 * std::fabs(want))
      mismatch(what, std::to_string(had), std::to_string(want));
  };
  check_float("quant_step_scale", "quantization step scale", o.quant_step_scale);
  check_float("qat_start", "quantization-aware start", o.qat_start);
  if (m.value("mlp_levels", 0) != o.mlp_levels) {
    mismatch("MLP levels", std::to_string(m.value("mlp_levels", 0)), std::to_string(o.mlp_levels));
  }
}

// The lambda = 0 float model of an earlier sweep, usable when this sweep trains it the same way.
}  // namespace

nlohmann::json BorrowReference(const std::string& dir, const nlohmann::json& sweep,
                               const std::string& data) {
  const nlohmann::json other = ReadReport(dir);
  if (!other.contains("reference") || other["reference"].is_null()) {
    throw std::runtime_error(dir + "/report.json: has no lambda = 0 reference to borrow");
  }
  if (!SameData(other.value("data", ""), data)) {
    throw std::runtime_error(dir + "/report.json: reference of data " + other.value("data", "?") +
                             ", this sweep is of " + data);
  }
  // The yardstick of every ratio is the preset's lambda = 0 model at the preset's own schedule, so
  // a sweep trained longer (e.g. --iters 4500) still measures against the 3000-iteration `fast`
  // reference; any other iteration count has to match the sweep's.
  const nlohmann::json other_iters =
      other.contains("sweep") ? other["sweep"].value("iterations", nlohmann::json()) : nullptr;
  const bool preset_schedule =
      other_iters.is_number_integer() &&
      other_iters.get<int>() ==
          trainer::PresetOptions(sweep.at("preset").get<std::string>()).reference_iters;
  for (const char* key :
       {"preset", "iterations", "seed", "test_view_stride", "max_test_views", "downscale"}) {
    if (std::string(key) == "iterations" && preset_schedule) continue;
    if (!other.contains("sweep") || other["sweep"].value(key, nlohmann::json()) != sweep.at(key)) {
      throw std::runtime_error(
          dir + "/report.json: its sweep has " + key + " " +
          (other.contains("sweep") ? other["sweep"].value(key, nlohmann::json()).dump() : "?") +
          ", this one " + sweep.at(key).dump() + "; its reference does not apply");
    }
  }
  nlohmann::json ref = other["reference"];
  ref["label"] = "lambda=0 float32 model, " + other_iters.dump() + " iterations (from " + dir + ")";
  return ref;
}

namespace {

std::string Minutes(double seconds) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f min", seconds / 60.0);
  return text;
}

// The arguments that are not the sweep's own: what every point's `ecrf train` line shares.
std::vector<std::string> TrainArgs(const std::vector<std::string>& args) {
  std::vector<std::string> out;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    bool with_value = false, sweep_flag = a == "--render" || a == "--plan" || a == "--collect";
    for (const char* f : {"--lambdas", "--rates", "--targets", "--anchors", "--reference", "-o",
                          "--out", "--task-cpus"}) {
      if (a == f) with_value = sweep_flag = true;
      if (a.rfind(std::string(f) + "=", 0) == 0) sweep_flag = true;
    }
    if (with_value) ++i;
    if (!sweep_flag) out.push_back(a);
  }
  return out;
}

// The arguments without --threads (a planned task takes its thread count from where it runs).
std::vector<std::string> WithoutThreads(const std::vector<std::string>& args) {
  std::vector<std::string> out;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--threads") {
      ++i;
    } else if (args[i].rfind("--threads=", 0) != 0) {
      out.push_back(args[i]);
    }
  }
  return out;
}

// `path` from the root (relative paths are relative to the current directory; "" is it).
std::string AbsolutePath(const std::string& path) {
  if (!path.empty() && path[0] == '/') return path;
  char cwd[PATH_MAX];
  if (!getcwd(cwd, sizeof(cwd))) throw std::runtime_error("cannot read the current directory");
  return path.empty() ? std::string(cwd) : std::string(cwd) + "/" + path;
}

std::string ProgramPath() {
  char path[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", path, sizeof(path) - 1);
  if (n <= 0) return "ecrf";
  path[n] = '\0';
  return path;
}

}  // namespace

int RunReportSweep(int argc, char** argv) {
  auto app = MakeCommand(
      "report sweep",
      "One `ecrf train` run per rate point, each encoded, decoded and scored, then the "
      "rate-distortion report. Each point is the run `ecrf train` makes with the shared flags "
      "plus --rate R (for --rates), --target-size S (for --targets) or --lambda-e X (for "
      "--lambdas, on the same base as train: the medium point unless --rate or --preset say "
      "otherwise), so both write the same bytes.\n"
      "usage: ecrf report sweep (--data DIR | --scene NAME) (--rates R,... | --targets S,... | "
      "--lambdas L,...) -o REPORT_DIR [train options]");
  const std::vector<std::string> args(argv + 1, argv + argc);
  TrainFlags flags;
  flags.options = BaseTrainOptions(args);
  AddTrainFlags(app.get(), &flags);
  std::string out, lambdas_text, rates_text, targets_text, anchors_path, reference_dir;
  bool render = false, plan = false, collect = false;
  int task_cpus = 4;
  app->add_option("-o,--out", out, "report directory (runs/ holds one run per point)")
      ->type_name("REPORT_DIR");
  app->add_flag("--plan", plan,
                "train nothing: write REPORT_DIR/plan/, one task per point (a finished point's "
                "task exits at once) for a Slurm job array (sweep.sbatch), GNU parallel or one "
                "after another (run_local.sh), and collect.sh, which reports them "
                "(docs/cluster.md)");
  app->add_flag("--collect", collect,
                "train nothing: report the finished points; name each unfinished one with its "
                "plan log and exit 1")
      ->excludes("--plan");
  app->add_option("--task-cpus", task_cpus,
                  "with --plan: CPUs per Slurm array task (the task trains on that many threads)")
      ->type_name("N")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  app->add_option("--rates", rates_text,
                  "named rate points, one run each (e.g. low,medium,high; none: lambda_e 0)")
      ->type_name("R1,R2,...");
  app->add_option("--targets", targets_text,
                  "file sizes, one `ecrf train --target-size` run each (e.g. 316KB,127KB: the "
                  "settings of the nearest rate point, lambda_e adapted while training)")
      ->type_name("S1,S2,...");
  app->add_option(
         "--lambdas", lambdas_text,
         "one run per lambda_e on the base; L@S also sets the step scale S (e.g. 0,1e-10,5e-11@2); "
         "0 is the plain TensoRF reference")
      ->type_name("L1,L2@S,...");
  app->add_option("--anchors", anchors_path,
                  "reference points drawn on the plots (docs/reports/anchors_paper.json)")
      ->type_name("FILE.json");
  app->add_flag("--render", render, "also run the speed-error sweep (as `ecrf report render`)");
  app->add_option("--reference", reference_dir,
                  "without a lambda_e 0 point: take the float32 reference of that earlier sweep "
                  "(same data, preset, "
                  "iterations, seed, stride)")
      ->type_name("REPORT_DIR");
  trainer::TrainOptions o;
  if (const int rc = ParseTrainCommandLine(app.get(), &flags, argc, argv, &o); rc >= 0) return rc;
  if (out.empty() || (lambdas_text.empty() && rates_text.empty() && targets_text.empty()) ||
      trainer::DataSource(o).empty()) {
    std::fprintf(
        stderr,
        "ecrf report sweep: error: needs --data DIR or --scene NAME, --rates, --targets or "
        "--lambdas, and -o; "
        "see 'ecrf report sweep --help'\n");
    return 2;
  }
  std::vector<SweepPoint> points = ParseRates(rates_text);
  for (const SweepPoint& p : ParseTargets(targets_text)) points.push_back(p);
  for (const SweepPoint& p : ParsePoints(lambdas_text)) points.push_back(p);
  // Each point's options, resolved as `ecrf train` resolves its command line. Every point scores
  // the float model too (the report's quantization-loss column), on every 10th test view unless
  // told (the views of every ecrf compression figure), 1 for the small procedural scenes.
  std::vector<std::string> train_args = TrainArgs(args);
  if (!app->count("--test-stride")) {
    train_args.insert(
        train_args.end(),
        {"--test-stride", o.procedural_scene == trainer::ProceduralScene::kNone ? "10" : "1"});
  }
  if (!app->count("--eval-every"))
    train_args.insert(train_args.end(), {"--eval-every", std::to_string(std::max(1, o.iters / 4))});
  train_args.push_back("--score-float");
  std::vector<trainer::TrainOptions> runs;
  std::vector<std::string> names;
  for (const SweepPoint& p : points) {
    std::vector<std::string> point_args = train_args;
    for (const std::string& a : PointArgs(p)) point_args.push_back(a);
    runs.push_back(ResolveTrainOptions(point_args));
    names.push_back(PointName(p, runs.back()));
  }
  o = runs.front();
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
  std::vector<double> lambdas, step_scales;
  std::vector<std::string> rate_points;
  for (size_t k = 0; k < runs.size(); ++k) {
    lambdas.push_back(runs[k].lambda_e);
    step_scales.push_back(runs[k].quant_step_scale);
    rate_points.push_back(!points[k].target.empty() ? "target " + points[k].target
                          : points[k].rate.empty()
                              ? std::string(trainer::NameOf(runs[k].rate_point)) + " base"
                              : points[k].rate);
  }
  report["scene"] = SceneName(o);
  report["data"] = trainer::DataSource(o);
  report["sweep"] = {{"preset", trainer::NameOf(o.preset)},
                     {"iterations", o.iters},
                     {"lambdas", lambdas},
                     {"step_scales", step_scales},
                     {"rate_points", rate_points},
                     {"alpha", o.alpha},
                     {"test_view_stride", o.test_view_stride},
                     {"max_test_views", o.max_test_views},
                     {"eval_every", o.eval_every},
                     {"seed", o.seed},
                     {"downscale", o.downscale},
                     {"threads", omp_get_max_threads()}};
  report["machine"] = {{"cpu", CpuModel()},
                       {"hardware_threads", std::thread::hardware_concurrency()}};
  report["ecrf_version"] = ecrf_version_string();
  report["bitstream_version"] = ecrf_bitstream_version();
  report["date"] = Today();
  report["anchors"] = anchors;
  report.erase("borrowed_reference");
  if (!reference_dir.empty()) {
    report["borrowed_reference"] =
        BorrowReference(reference_dir, report["sweep"], report["data"].get<std::string>());
  }
  report["points"] = nlohmann::json::array();

  const std::string plan_dir = AbsolutePath(out) + "/plan";
  if (plan) {
    SweepPlan p;
    p.plan_dir = plan_dir;
    p.ecrf = ProgramPath();
    p.work_dir = AbsolutePath("");
    p.job_name = "ecrf-sweep-" + SceneName(o);
    p.task_cpus = task_cpus;
    size_t finished = 0;
    for (size_t k = 0; k < runs.size(); ++k) {
      const std::string run_dir = out + "/runs/" + names[k];
      if (FileExists(run_dir + "/metrics.json")) {
        CheckReusable(ReadJsonFile(run_dir + "/metrics.json"), runs[k], run_dir + "/metrics.json");
        ++finished;
      }
      std::vector<std::string> point_args = WithoutThreads(train_args);
      for (const std::string& a : PointArgs(points[k])) point_args.push_back(a);
      p.tasks.push_back({names[k], run_dir, point_args});
    }
    // The sweep's own command line, --plan replaced by --collect.
    p.collect_args = {"report", "sweep"};
    for (size_t i = 0; i < args.size(); ++i) {
      if (args[i] == "--task-cpus") {
        ++i;
      } else if (args[i] != "--plan" && args[i].rfind("--task-cpus=", 0) != 0) {
        p.collect_args.push_back(args[i]);
      }
    }
    p.collect_args.push_back("--collect");
    WriteSweepPlan(p);
    std::printf(
        "plan: %zu tasks (%zu finished already) in %s\n"
        "  Slurm:      sbatch %s/sweep.sbatch   (a job array, %d CPUs per task)\n"
        "  this host:  bash %s/run_local.sh [JOBS]   (GNU parallel for JOBS > 1)\n"
        "  then:       bash %s/collect.sh   (the report; names any task that did not finish)\n",
        p.tasks.size(), finished, plan_dir.c_str(), plan_dir.c_str(), task_cpus, plan_dir.c_str(),
        plan_dir.c_str());
    return 0;
  }

  double trained_seconds = 0.0;
  int trained = 0;
  std::vector<std::string> unfinished;
  for (size_t k = 0; k < runs.size(); ++k) {
    trainer::TrainOptions run = runs[k];
    const std::string run_dir = out + "/runs/" + names[k];
    const std::string metrics_path = run_dir + "/metrics.json";
    nlohmann::json metrics;
    if (FileExists(metrics_path)) {
      metrics = ReadJsonFile(metrics_path);
      CheckReusable(metrics, run, metrics_path);
      std::fprintf(stderr, "report: point %zu/%zu (%s): reusing the finished run in %s\n", k + 1,
                   runs.size(), names[k].c_str(), run_dir.c_str());
    } else if (collect) {
      const std::string log = TaskLogPath(plan_dir, k);
      const std::string tail = LastLines(log, 6);
      std::fprintf(
          stderr, "report: point %zu/%zu (%s): not finished: no %s; task %zu's log %s%s\n%s", k + 1,
          runs.size(), names[k].c_str(), metrics_path.c_str(), k, log.c_str(),
          tail.empty() ? " does not exist (the task has not run)" : " ends:", tail.c_str());
      unfinished.push_back(names[k] + " (task " + std::to_string(k) + ", log " + log + ")");
      continue;
    } else {
      size_t left = 0;
      for (size_t j = k; j < runs.size(); ++j)
        left += !FileExists(out + "/runs/" + names[j] + "/metrics.json");
      const std::string eta = trained ? "sweep ETA " + Minutes(trained_seconds / trained * left)
                                      : "sweep ETA known after the first point";
      std::fprintf(stderr, "report: point %zu/%zu (%s): training into %s; %zu to train, %s\n",
                   k + 1, runs.size(), names[k].c_str(), run_dir.c_str(), left, eta.c_str());
      run.out_dir = run_dir;
      run.overwrite = true;  // a point the sweep left unfinished is trained again from the start
      const auto start = std::chrono::steady_clock::now();
      metrics = TrainEncodeEvaluate(run);
      trained_seconds += trainer::SecondsSince(start);
      ++trained;
    }
    nlohmann::json point = RatePointFromMetrics(metrics, "runs/" + names[k]);
    point["rate_point"] = rate_points[k];
    if (!points[k].rate.empty() || !points[k].target.empty())
      point["label"] = rate_points[k] + " (" + point["label"].get<std::string>() + ")";
    // The point's whole configuration: what `ecrf train` needs to write the same file.
    point["config"] = nlohmann::json::parse(trainer::TrainConfigToJson(run, -1));
    point["config"]["bookkeeping"].erase("out_dir");
    report["points"].push_back(point);
    AddReferenceColumns(&report);
    WriteReport(out, report);
  }
  if (!unfinished.empty()) {
    std::fprintf(stderr, "report: %zu of %zu points did not finish:\n", unfinished.size(),
                 runs.size());
    for (const std::string& u : unfinished) std::fprintf(stderr, "  %s\n", u.c_str());
    std::fprintf(stderr,
                 "resubmit the plan (finished points are skipped) and collect again; the report "
                 "in %s holds the finished points\n",
                 out.c_str());
    return 1;
  }
  if (render) RunSpeedSweep(out, SpeedSweepOptions(), &report);
  std::printf("%-24s %10s %8s %10s %10s %9s %10s\n", "point", "bytes", "ratio", "decoded", "float",
              "loss", "train");
  for (const nlohmann::json& p : report["points"]) {
    auto number = [](const nlohmann::json& x) { return x.is_null() ? NAN : x.get<double>(); };
    const double loss = number(p["psnr_loss_db"]);
    std::printf("%-24s %10lld %7.1fx %7.2f dB %7.2f dB %+6.2f dB %10s\n",
                p["label"].get<std::string>().c_str(), p["file_bytes"].get<long long>(),
                p["ratio"].get<double>(), p["decoded_psnr"].get<double>(), number(p["float_psnr"]),
                loss, Minutes(p["train_seconds"].get<double>()).c_str());
  }
  std::printf("report: %s/index.html (report.json, CSV files and plots beside it)\n", out.c_str());
  return 0;
}

}  // namespace tools
}  // namespace ecrf
