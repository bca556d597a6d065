// `ecrf report sweep`: one training run per lambda_e, each encoded, decoded and scored, then the
// rate–distortion report. Finished runs in REPORT/runs/ are reused, so an interrupted sweep
// resumes where it stopped, and the report is rewritten after every point. With --plan the points
// become a plan of independent tasks for Slurm or GNU parallel (sweep_plan.h), and --collect
// reports what those tasks finished without training anything.
#include <omp.h>

#include <strings.h>
#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "ecrf/decoder.h"
#include "tools/cli_args.h"
#include "tools/report/report.h"
#include "tools/report/report_speed.h"
#include "tools/report/sweep_plan.h"
#include "tools/report/sweep_points.h"
#include "tools/train_flags.h"
#include "tools/train_run.h"
#include "trainer/data/seconds_since.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/train_config.h"
#include "trainer/train/train_options.h"
#include "trainer/train/trainer.h"

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

}  // namespace

nlohmann::json ReadAnchors(const std::string& path, const std::string& scene) {
  nlohmann::json kept = nlohmann::json::array();
  if (path.empty()) return kept;
  const nlohmann::json a = ReadJsonFile(path);
  if (!a.contains("anchors") || !a["anchors"].is_array()) {
    throw std::runtime_error(path + ": expected {\"anchors\": [{\"label\": ..., ...}]}");
  }
  for (size_t i = 0; i < a["anchors"].size(); ++i) {
    const nlohmann::json& e = a["anchors"][i];
    const auto number = [&e](const char* key) { return e.contains(key) && e[key].is_number(); };
    if (!e.is_object() || !e.contains("label") || !e["label"].is_string() ||
        (e.contains("scene") && !e["scene"].is_string()) ||
        !((number("file_bytes") && number("psnr")) ||
          (number("ratio") && number("psnr_loss_db")))) {
      throw std::runtime_error(path + ": anchor " + std::to_string(i) +
                               " needs a \"label\" (and a \"scene\" name, if any) and numbers "
                               "\"file_bytes\" and \"psnr\" or "
                               "\"ratio\" and \"psnr_loss_db\"");
    }
    if (e.contains("scene") && strcasecmp(e.value("scene", "").c_str(), scene.c_str()) != 0) {
      continue;
    }
    kept.push_back(e);
  }
  return kept;
}

// The lambda = 0 float model of an earlier sweep, usable when this sweep trains it the same way.
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

// The flags of `ecrf report sweep` beyond the `ecrf train` flags every point shares.
struct SweepFlags {
  std::string out, lambdas_text, rates_text, targets_text, anchors_path, reference_dir;
  bool render = false, plan = false, collect = false;
  int task_cpus = 4;
};

void AddSweepFlags(CLI::App* app, SweepFlags* f) {
  app->add_option("-o,--out", f->out, "report directory (runs/ holds one run per point)")
      ->type_name("REPORT_DIR");
  app->add_flag("--plan", f->plan,
                "train nothing: write REPORT_DIR/plan/, one task per point (a finished point's "
                "task exits at once) for a Slurm job array (sweep.sbatch), GNU parallel or one "
                "after another (run_local.sh), and collect.sh, which reports them "
                "(docs/cluster.md)");
  app->add_flag("--collect", f->collect,
                "train nothing: report the finished points; name each unfinished one with its "
                "plan log and exit 1")
      ->excludes("--plan");
  app->add_option("--task-cpus", f->task_cpus,
                  "with --plan: CPUs per Slurm array task (the task trains on that many threads)")
      ->type_name("N")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  app->add_option("--rates", f->rates_text,
                  "named rate points, one run each (e.g. low,medium,high; none: lambda_e 0)")
      ->type_name("R1,R2,...");
  app->add_option("--targets", f->targets_text,
                  "file sizes, one `ecrf train --target-size` run each (e.g. 316KB,127KB: the "
                  "settings of the nearest rate point, lambda_e adapted while training)")
      ->type_name("S1,S2,...");
  app->add_option(
         "--lambdas", f->lambdas_text,
         "one run per lambda_e on the base; L@S also sets the step scale S (e.g. 0,1e-10,5e-11@2); "
         "0 is the plain TensoRF reference")
      ->type_name("L1,L2@S,...");
  app->add_option("--anchors", f->anchors_path,
                  "reference points drawn on the plots (docs/reports/anchors_paper.json)")
      ->type_name("FILE.json");
  app->add_flag("--render", f->render, "also run the speed-error sweep (as `ecrf report render`)");
  app->add_option("--reference", f->reference_dir,
                  "without a lambda_e 0 point: take the float32 reference of that earlier sweep "
                  "(same data, preset, "
                  "iterations, seed, stride)")
      ->type_name("REPORT_DIR");
}

// The sweep's points, each with the options `ecrf train` would resolve from its command line.
struct SweepRuns {
  std::vector<SweepPoint> points;
  std::vector<std::string> train_args;         // the `ecrf train` arguments every point shares
  std::vector<trainer::TrainOptions> options;  // per point
  std::vector<std::string> names;              // per point: its run directory under runs/
  std::vector<std::string> rate_points;        // per point: the report's rate point column
};

// The report's rate point of a point: its --rate or --target-size, or for a lambda the rate point
// whose settings it trains on.
std::string RatePointLabel(const SweepPoint& p, const trainer::TrainOptions& resolved) {
  if (!p.target.empty()) return "target " + p.target;
  return p.rate.empty() ? std::string(trainer::NameOf(resolved.rate_point)) + " base" : p.rate;
}

// Each point's options, resolved as `ecrf train` resolves its command line. Every point scores
// the float model too (the report's quantization-loss column), on every 10th test view unless
// told (the views of every ecrf compression figure), 1 for the small procedural scenes.
SweepRuns ResolveSweepRuns(const CLI::App& app, const std::vector<std::string>& args,
                           const SweepFlags& f, const trainer::TrainOptions& o) {
  SweepRuns sweep;
  sweep.points = ParseSweepPoints(f.rates_text, f.targets_text, f.lambdas_text);
  sweep.train_args = TrainArgs(args);
  std::vector<std::string>& train_args = sweep.train_args;
  if (!app.count("--test-stride")) {
    train_args.insert(
        train_args.end(),
        {"--test-stride", o.procedural_scene == trainer::ProceduralScene::kNone ? "10" : "1"});
  }
  if (!app.count("--eval-every"))
    train_args.insert(train_args.end(), {"--eval-every", std::to_string(std::max(1, o.iters / 4))});
  train_args.push_back("--score-float");
  for (const SweepPoint& p : sweep.points) {
    std::vector<std::string> point_args = train_args;
    for (const std::string& a : PointArgs(p)) point_args.push_back(a);
    sweep.options.push_back(ResolveTrainOptions(point_args));
    sweep.names.push_back(PointName(p, sweep.options.back()));
    sweep.rate_points.push_back(RatePointLabel(p, sweep.options.back()));
  }
  return sweep;
}

// The report before its points: what was swept, on which machine and version, and the reference
// borrowed from an earlier sweep. An earlier REPORT/report.json keeps its speed section.
nlohmann::json SweepReportHead(const SweepFlags& f, const SweepRuns& sweep,
                               const trainer::TrainOptions& o, const nlohmann::json& anchors) {
  nlohmann::json report;
  if (FileExists(f.out + "/report.json")) report = ReadReport(f.out);
  std::vector<double> lambdas, step_scales;
  for (const trainer::TrainOptions& run : sweep.options) {
    lambdas.push_back(run.lambda_e);
    step_scales.push_back(run.quant_step_scale);
  }
  report["scene"] = SceneName(o);
  report["data"] = trainer::DataSource(o);
  report["sweep"] = {{"preset", trainer::NameOf(o.preset)},
                     {"iterations", o.iters},
                     {"lambdas", lambdas},
                     {"step_scales", step_scales},
                     {"rate_points", sweep.rate_points},
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
  if (!f.reference_dir.empty()) {
    report["borrowed_reference"] =
        BorrowReference(f.reference_dir, report["sweep"], report["data"].get<std::string>());
  }
  report["points"] = nlohmann::json::array();
  return report;
}

// The sweep's own command line, --plan (and --task-cpus) replaced by --collect.
std::vector<std::string> CollectArgs(const std::vector<std::string>& args) {
  std::vector<std::string> collect_args = {"report", "sweep"};
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--task-cpus") {
      ++i;
    } else if (args[i] != "--plan" && args[i].rfind("--task-cpus=", 0) != 0) {
      collect_args.push_back(args[i]);
    }
  }
  collect_args.push_back("--collect");
  return collect_args;
}

// --plan: writes the plan of one task per point (finished points checked as reusable) and says
// how to run it.
int PlanSweep(const SweepFlags& f, const std::vector<std::string>& args, const SweepRuns& sweep,
              const std::string& plan_dir, const std::string& scene) {
  SweepPlan p;
  p.plan_dir = plan_dir;
  p.ecrf = ProgramPath();
  p.work_dir = AbsolutePath("");
  p.job_name = "ecrf-sweep-" + scene;
  p.task_cpus = f.task_cpus;
  size_t finished = 0;
  for (size_t k = 0; k < sweep.options.size(); ++k) {
    const std::string run_dir = f.out + "/runs/" + sweep.names[k];
    if (FileExists(run_dir + "/metrics.json")) {
      CheckReusable(ReadJsonFile(run_dir + "/metrics.json"), sweep.options[k],
                    run_dir + "/metrics.json");
      ++finished;
    }
    std::vector<std::string> point_args = WithoutThreads(sweep.train_args);
    for (const std::string& a : PointArgs(sweep.points[k])) point_args.push_back(a);
    p.tasks.push_back({sweep.names[k], run_dir, point_args});
  }
  p.collect_args = CollectArgs(args);
  WriteSweepPlan(p);
  std::printf(
      "plan: %zu tasks (%zu finished already) in %s\n"
      "  Slurm:      sbatch %s/sweep.sbatch   (a job array, %d CPUs per task)\n"
      "  this host:  bash %s/run_local.sh [JOBS]   (GNU parallel for JOBS > 1)\n"
      "  then:       bash %s/collect.sh   (the report; names any task that did not finish)\n",
      p.tasks.size(), finished, plan_dir.c_str(), plan_dir.c_str(), f.task_cpus, plan_dir.c_str(),
      plan_dir.c_str());
  return 0;
}

// The time the points trained so far took, for the sweep's ETA.
struct TrainingPace {
  double seconds = 0.0;
  int trained = 0;
};

// Trains point k into its run directory (continuing the checkpoint of an earlier sweep's
// unfinished run of the same settings, else from the start), first saying how many points are left
// to train and when the sweep should end.
nlohmann::json TrainPoint(const SweepRuns& sweep, size_t k, const std::string& out,
                          TrainingPace* pace, trainer::TrainOptions* run) {
  const std::string run_dir = out + "/runs/" + sweep.names[k];
  const size_t count = sweep.options.size();
  size_t left = 0;
  for (size_t j = k; j < count; ++j)
    left += !FileExists(out + "/runs/" + sweep.names[j] + "/metrics.json");
  const std::string eta = pace->trained
                              ? "sweep ETA " + Minutes(pace->seconds / pace->trained * left)
                              : "sweep ETA known after the first point";
  std::fprintf(stderr, "report: point %zu/%zu (%s): training into %s; %zu to train, %s\n", k + 1,
               count, sweep.names[k].c_str(), run_dir.c_str(), left, eta.c_str());
  run->out_dir = run_dir;
  run->resume = CanResume(*run);  // stopped by Ctrl-C or SIGTERM, or killed after a checkpoint
  run->overwrite = !run->resume;
  if (run->resume)
    std::fprintf(stderr, "report: continuing %s from its checkpoint\n", run_dir.c_str());
  const auto start = std::chrono::steady_clock::now();
  nlohmann::json metrics = TrainEncodeEvaluate(*run);
  pace->seconds += trainer::SecondsSince(start);
  ++pace->trained;
  return metrics;
}

// --collect, point k not finished: says so with the end of its task's log; returns the line the
// summary of unfinished points gives it.
std::string ReportUnfinished(const SweepRuns& sweep, size_t k, const std::string& plan_dir,
                             const std::string& metrics_path) {
  const std::string log = TaskLogPath(plan_dir, k);
  const std::string tail = LastLines(log, 6);
  std::fprintf(stderr, "report: point %zu/%zu (%s): not finished: no %s; task %zu's log %s%s\n%s",
               k + 1, sweep.options.size(), sweep.names[k].c_str(), metrics_path.c_str(), k,
               log.c_str(),
               tail.empty() ? " does not exist (the task has not run)" : " ends:", tail.c_str());
  return sweep.names[k] + " (task " + std::to_string(k) + ", log " + log + ")";
}

// The report's entry of point k from its run's metrics, with the point's whole configuration:
// what `ecrf train` needs to write the same file.
nlohmann::json ReportPoint(const nlohmann::json& metrics, const SweepRuns& sweep, size_t k,
                           const trainer::TrainOptions& run) {
  nlohmann::json point = RatePointFromMetrics(metrics, "runs/" + sweep.names[k]);
  point["rate_point"] = sweep.rate_points[k];
  if (!sweep.points[k].rate.empty() || !sweep.points[k].target.empty())
    point["label"] = sweep.rate_points[k] + " (" + point["label"].get<std::string>() + ")";
  point["config"] = nlohmann::json::parse(trainer::TrainConfigToJson(run, -1));
  point["config"]["bookkeeping"].erase("out_dir");
  return point;
}

// Adds every point to the report, rewriting it after each: a finished run is reused, an
// unfinished one trained (or with --collect, named). Returns the unfinished points' lines.
std::vector<std::string> RunPoints(const SweepFlags& f, const SweepRuns& sweep,
                                   const std::string& plan_dir, nlohmann::json* report) {
  TrainingPace pace;
  std::vector<std::string> unfinished;
  for (size_t k = 0; k < sweep.options.size(); ++k) {
    trainer::TrainOptions run = sweep.options[k];
    const std::string run_dir = f.out + "/runs/" + sweep.names[k];
    const std::string metrics_path = run_dir + "/metrics.json";
    nlohmann::json metrics;
    if (FileExists(metrics_path)) {
      metrics = ReadJsonFile(metrics_path);
      CheckReusable(metrics, run, metrics_path);
      std::fprintf(stderr, "report: point %zu/%zu (%s): reusing the finished run in %s\n", k + 1,
                   sweep.options.size(), sweep.names[k].c_str(), run_dir.c_str());
    } else if (f.collect) {
      unfinished.push_back(ReportUnfinished(sweep, k, plan_dir, metrics_path));
      continue;
    } else {
      metrics = TrainPoint(sweep, k, f.out, &pace, &run);
    }
    (*report)["points"].push_back(ReportPoint(metrics, sweep, k, run));
    AddReferenceColumns(report);
    WriteReport(f.out, *report);
  }
  return unfinished;
}

void PrintUnfinished(const std::vector<std::string>& unfinished, size_t points,
                     const std::string& out) {
  std::fprintf(stderr, "report: %zu of %zu points did not finish:\n", unfinished.size(), points);
  for (const std::string& u : unfinished) std::fprintf(stderr, "  %s\n", u.c_str());
  std::fprintf(stderr,
               "resubmit the plan (finished points are skipped) and collect again; the report "
               "in %s holds the finished points\n",
               out.c_str());
}

// One line per point: size, ratio, decoded and float PSNR, quantization loss, training time; "-"
// where a point has no such figure (no float score, no lambda = 0 reference).
void PrintPointTable(const nlohmann::json& report) {
  size_t width = 5;
  for (const nlohmann::json& p : report["points"])
    width = std::max(width, p["label"].get<std::string>().size());
  auto cell = [](const nlohmann::json& x, const char* format) {
    if (!x.is_number() || !std::isfinite(x.get<double>())) return std::string("-");
    char text[32];
    std::snprintf(text, sizeof(text), format, x.get<double>());
    return std::string(text);
  };
  std::printf("%-*s %10s %8s %10s %10s %9s %10s\n", int(width), "point", "bytes", "ratio",
              "decoded", "float", "loss", "train");
  for (const nlohmann::json& p : report["points"]) {
    std::printf("%-*s %10lld %8s %10s %10s %9s %10s\n", int(width),
                p["label"].get<std::string>().c_str(), p["file_bytes"].get<long long>(),
                cell(p["ratio"], "%.1fx").c_str(), cell(p["decoded_psnr"], "%.2f dB").c_str(),
                cell(p["float_psnr"], "%.2f dB").c_str(),
                cell(p["psnr_loss_db"], "%+.2f dB").c_str(),
                Minutes(p["train_seconds"].get<double>()).c_str());
  }
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
  SweepFlags f;
  AddSweepFlags(app.get(), &f);
  trainer::TrainOptions o;
  if (const int rc = ParseTrainCommandLine(app.get(), &flags, argc, argv, &o); rc >= 0) return rc;
  if (f.out.empty() || (f.lambdas_text.empty() && f.rates_text.empty() && f.targets_text.empty()) ||
      trainer::DataSource(o).empty()) {
    std::fprintf(
        stderr,
        "ecrf report sweep: error: needs --data DIR or --scene NAME, --rates, --targets or "
        "--lambdas, and -o; "
        "see 'ecrf report sweep --help'\n");
    return 2;
  }
  const SweepRuns sweep = ResolveSweepRuns(*app, args, f, o);
  o = sweep.options.front();
  const nlohmann::json anchors = ReadAnchors(f.anchors_path, SceneName(o));
  // Find an unusable output directory now, not after the first hour of training.
  const OutputDirectory runs_dir(f.out + "/runs");
  nlohmann::json report = SweepReportHead(f, sweep, o, anchors);
  const std::string plan_dir = AbsolutePath(f.out) + "/plan";
  if (f.plan) return PlanSweep(f, args, sweep, plan_dir, SceneName(o));
  std::vector<std::string> unfinished;
  try {
    unfinished = RunPoints(f, sweep, plan_dir, &report);
  } catch (const trainer::TrainingStopped& e) {  // Ctrl-C or SIGTERM: the point's checkpoint
    std::fprintf(stderr, "report: %s; the same command continues the sweep from there\n", e.what());
    return e.signal() != 0 ? 128 + e.signal() : 1;
  }
  if (!unfinished.empty()) {
    PrintUnfinished(unfinished, sweep.options.size(), f.out);
    return 1;
  }
  if (f.render) RunSpeedSweep(f.out, SpeedSweepOptions(), &report);
  PrintPointTable(report);
  std::printf("report: %s/index.html (report.json, CSV files and plots beside it)\n",
              f.out.c_str());
  return 0;
}

}  // namespace tools
}  // namespace ecrf
