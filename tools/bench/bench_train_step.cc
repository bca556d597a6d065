// `ecrf bench train`: times one training iteration as the trainer runs it in its rate phase,
// phase by phase (zero the gradients, quantization-aware refresh and apply, TrainStep = march,
// head, composite and scatter, density L1, the rate term, Adam on grids and head) on a synthetic
// Blender-like scene: aabb [-1.5,1.5]^3, cameras on a sphere of radius 4, an opaque soft blob in
// the middle of a randomly initialised VM-192 field, or (--run RUN) a trained run's own model and
// settings, whose grid and mask a real scene's step pays for, with the same rays; at each thread
// count asked for. It then prints the scaling table: per phase the measured times, the fitted
// serial fraction and the predicted times at 8-64 threads with what bounds each (scaling_model.h),
// so the same command gives the figure on any machine. Flags and their defaults: `ecrf bench train
// --help`.
#include <omp.h>
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "tools/bench/bench_json.h"
#include "tools/bench/cpu_peak.h"
#include "tools/bench/scaling_model.h"
#include "tools/bench/work_counts.h"
#include "tools/cli_args.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/quant_aware.h"
#include "trainer/train/adam.h"
#include "trainer/train/rate_state.h"
#include "trainer/train/train_options.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {

int RunTrainStepBench(int argc, char** argv);

namespace {

using trainer::TensorfConfig;
using trainer::TensorfModel;
using trainer::TrainStepStats;
using trainer::VmGrid;

double CpuSeconds() {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_utime.tv_sec + ru.ru_stime.tv_sec +
         1e-6 * (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

double PeakRssMb() {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0;
}

// Adds a soft ellipsoidal blob to rank 0 of density mode 0 (plane xy * line z):
// feature = peak * max(0, 1 - 2 r_xy^2) * max(0, 1 - 2 r_z^2) in normalized coordinates.
void AddBlob(TensorfModel& model, float peak) {
  VmGrid& g = model.density();
  const auto& res = model.res();
  for (int y = 0; y < res[1]; ++y)
    for (int x = 0; x < res[0]; ++x) {
      const float u = 2.f * x / (res[0] - 1) - 1.f, v = 2.f * y / (res[1] - 1) - 1.f;
      g.PlaneAt(0, y, x, 0) = std::sqrt(peak) * std::max(0.f, 1.f - 2.f * (u * u + v * v));
    }
  for (int z = 0; z < res[2]; ++z) {
    const float w = 2.f * z / (res[2] - 1) - 1.f;
    g.LineAt(0, z, 0) = std::sqrt(peak) * std::max(0.f, 1.f - 2.f * w * w);
  }
}

void MakeRays(int n, uint32_t seed, std::vector<float>* o, std::vector<float>* d,
              std::vector<float>* rgb) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> nd;
  std::uniform_real_distribution<float> u(-1.f, 1.f), c(0.f, 1.f);
  o->resize(3 * n);
  d->resize(3 * n);
  rgb->resize(3 * n);
  for (int i = 0; i < n; ++i) {
    float p[3] = {nd(rng), nd(rng), std::fabs(nd(rng))};  // upper hemisphere, as in Blender
    const float len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    float dir[3];
    for (int a = 0; a < 3; ++a) {
      (*o)[3 * i + a] = 4.f * p[a] / len;
      dir[a] = 1.2f * u(rng) - (*o)[3 * i + a];
    }
    const float dl = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (int a = 0; a < 3; ++a) {
      (*d)[3 * i + a] = dir[a] / dl;
      (*rgb)[3 * i + a] = c(rng);
    }
  }
}

// Bytes per second of a[i] = b[i] + s c[i] over three 64 MB arrays on `threads` threads (best of
// three; 12 bytes per element, not counting write allocation): the memory bandwidth that the
// streaming phases (Adam, L1, zeroing, quantization-aware apply) can have.
double MeasureTriadBandwidth(int threads) {
  const long n = 16L << 20;
  std::vector<float> a(n), b(n, 1.f), c(n, 2.f);
  double best = 1e30;
  for (int rep = 0; rep < 4; ++rep) {
    const double t0 = omp_get_wtime();
#pragma omp parallel for schedule(static) num_threads(threads)
    for (long i = 0; i < n; ++i) a[i] = b[i] + 0.5f * c[i];
    const double dt = omp_get_wtime() - t0;
    if (rep > 0) best = std::min(best, dt);  // the first pass faults the pages in
  }
  return 12.0 * static_cast<double>(n) / best;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// The phases of one iteration, in the trainer's order.
enum Phase {
  kZero,
  kQatRefresh,
  kQatApply,
  kMarch,
  kHead,
  kComposite,
  kScatter,
  kL1,
  kRate,
  kAdam,
  kNumPhases
};
const char* const kPhaseNames[kNumPhases] = {"zero grads", "qat refresh", "qat apply", "march",
                                             "head",       "composite",   "scatter",   "density L1",
                                             "rate term",  "adam"};
const char* const kPhaseKeys[kNumPhases] = {"zero", "qat_refresh", "qat_apply", "march",
                                            "head", "composite",   "scatter",   "l1",
                                            "rate", "adam"};

// The settings of `ecrf bench train`, as its command line gives them.
struct TrainStepBenchFlags {
  int res = 128, rays = 4096, reps = 5, mask = 0, rate_phase = 1;
  // The blob is an object scene with fixed cameras: ecrf train's auto early stop for it.
  float early = trainer::kAutoEarlyStop, blob_peak = 14.f, rdoq = 0.f;
  std::string threads = "1,2", json_path, run;
  std::string head = kHeadKindNames[0];  // where the MLP runs (SPEC.md 7.6)
  int mlp_layers = 2;                    // its hidden layers (ecrf train --mlp-layers)
};

void AddTrainStepBenchFlags(CLI::App* app, TrainStepBenchFlags* f) {
  app->add_option("--res", f->res, "grid resolution per axis")
      ->type_name("N")
      ->check(CLI::Range(2, 1024))
      ->capture_default_str();
  app->add_option("--rays", f->rays, "rays per batch")
      ->type_name("N")
      ->check(CLI::Range(1, 1 << 24))
      ->capture_default_str();
  app->add_option("--reps", f->reps, "timed steps per thread count (after one warm-up step)")
      ->type_name("N")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  AddThreadListFlag(app, &f->threads);
  app->add_option("--mask", f->mask,
                  "update the alpha mask (and shrink) before timing (0: no mask)")
      ->type_name("0|1")
      ->check(CLI::Range(0, 1))
      ->capture_default_str();
  app->add_option("--rate", f->rate_phase,
                  "1: the rate phase's iteration (rate term at the medium point's lambda_e, "
                  "quantization-aware training); 0: plain TensoRF's")
      ->type_name("0|1")
      ->check(CLI::Range(0, 1))
      ->capture_default_str();
  app->add_option("--rdoq", f->rdoq,
                  "the rate phase's quantizer: RDOQ with this lambda (0: rounding), as ecrf train "
                  "--rdoq")
      ->type_name("L")
      ->check(CLI::Range(0.0f, 10.0f))
      ->capture_default_str();
  app->add_option("--head", f->head,
                  "the appearance head: mlp (per coloured sample), deferred (per ray) or sh "
                  "(per ray, spherical harmonics), as ecrf train --head")
      ->type_name("NAME")
      ->check(CLI::IsMember(
          std::vector<std::string>{kHeadKindNames[0], kHeadKindNames[1], kShHeadName}))
      ->capture_default_str();
  app->add_option("--mlp-layers", f->mlp_layers,
                  "hidden layers of the MLP (mlp and deferred heads), as ecrf train --mlp-layers")
      ->type_name("N")
      ->check(CLI::Range(1, 2))
      ->capture_default_str();
  app->add_option("--early-stop", f->early,
                  "stop a ray once its transmittance is below T, as ecrf train --early-stop")
      ->type_name("T")
      ->check(CLI::Range(0.0f, 1.0f))
      ->capture_default_str();
  app->add_option(
         "--blob-peak", f->blob_peak,
         "peak density feature of the blob; larger -> more opaque -> fewer appearance samples per "
         "ray "
         "(e.g. 40 gives about the 0.14 M of the reference PyTorch run's iterations 150-320)")
      ->type_name("F")
      ->check(CLI::Range(0.0f, 1000.0f))
      ->capture_default_str();
  app->add_option("--run", f->run,
                  "time the step on a run's trained model (RUN/checkpoint.ckpt: its grids, mask, "
                  "head, settings and rate state) instead of the synthetic blob; --res, --mask, "
                  "--head, --mlp-layers, --early-stop and --blob-peak then do not apply")
      ->type_name("RUN");
  app->add_option("--json", f->json_path,
                  "also write the figures (per phase and thread count, and the predictions) as "
                  "JSON")
      ->type_name("FILE");
}

// What one timed iteration works on: the synthetic scene's model (or a run's), the rays, and the
// optimizer and rate state the trainer holds in its rate phase; and the field every step starts
// from.
struct StepBench {
  explicit StepBench(const TrainStepBenchFlags& f);

  trainer::RateState rate;  // before the model, which --run loads together with it
  TensorfModel model;
  std::vector<float> o, d, rgb;
  trainer::Adam adam_density, adam_app, adam_head;
  trainer::TrainOptions options;
  trainer::QuantAwareModel qat;
  std::vector<float> density0, app0, head0;
};

TensorfConfig BenchModelConfig(const TrainStepBenchFlags& f) {
  TensorfConfig config;
  config.early_stop_transmittance = f.early;
  for (int k = 0; k < kNumHeadKinds; ++k) {
    if (f.head == kHeadKindNames[k]) config.head.kind = static_cast<HeadKind>(k);
  }
  config.head.hidden_layers = f.mlp_layers;
  if (f.head == kShHeadName) {  // as ecrf train --head sh at its default degree: deferred, no MLP
    config.head.kind = HeadKind::kDeferred;
    config.head = trainer::ShHeadConfig(config.head, trainer::TrainOptions().sh_degree);
  }
  return config;
}

// The synthetic scene: the blob in a random field, masked and shrunk as the trainer does.
TensorfModel BlobModel(const TrainStepBenchFlags& f) {
  TensorfModel model(BenchModelConfig(f));
  model.Initialize({f.res, f.res, f.res}, 1);
  AddBlob(model, f.blob_peak);  // feature up to blob_peak: sigma up to softplus(peak - 10)
  if (f.mask) {
    const trainer::Aabb box = model.UpdateAlphaMask({f.res, f.res, f.res});
    model.Shrink(box);
  }
  return model;
}

std::string RunCheckpoint(const std::string& run) {
  return IsDirectory(run) ? run + "/checkpoint.ckpt" : run;
}

StepBench::StepBench(const TrainStepBenchFlags& f)
    : model(f.run.empty() ? BlobModel(f)
                          : trainer::LoadModelFromCheckpoint(RunCheckpoint(f.run), &rate)) {
  MakeRays(f.rays, 7, &o, &d, &rgb);
  // The trainer's optimizers (trainer.cc): grids at lr 0.02, head at 1e-3.
  adam_density = trainer::Adam(model.density().params().size(), trainer::AdamConfig{});
  adam_app = trainer::Adam(model.appearance().params().size(), trainer::AdamConfig{});
  adam_head = trainer::Adam(model.head().params().size(), trainer::AdamConfig{});
  if (!f.run.empty()) {
    // The run's own settings, and the lambda_e and steps its rate phase ended with.
    const trainer::CheckpointRunInfo info = trainer::ReadCheckpointRunInfo(RunCheckpoint(f.run));
    if (info.has_config) {
      options = info.config;
      // auto (< 0): the checkpoint's model holds what the run resolved it to.
      if (options.early_stop >= 0.f) model.SetEarlyStop(options.early_stop);
    }
    if (rate.checkpoint_lambda_e > 0.f) options.lambda_e = rate.checkpoint_lambda_e;
  } else {
    options.lambda_e = 3e-11f;  // the medium rate point's
    options.rdoq_lambda = f.rdoq;
  }
  if (f.rate_phase && !rate.active) rate.Activate(model, options);
  density0 = model.density().params();
  app0 = model.appearance().params();
  head0 = model.head().params();
}

// Bytes each streaming phase reads and writes per step (the memory-bandwidth floor).
std::array<double, kNumPhases> PhaseBytes(const TensorfModel& model, bool rate_phase) {
  const double grid_params =
      static_cast<double>(model.density().params().size() + model.appearance().params().size());
  const double all_params = grid_params + static_cast<double>(model.head().params().size());
  std::array<double, kNumPhases> bytes{};
  bytes[kZero] = 4.0 * all_params;
  bytes[kQatApply] = rate_phase ? 12.0 * all_params : 0.0;
  bytes[kL1] = 12.0 * static_cast<double>(model.density().params().size());
  bytes[kAdam] = 28.0 * all_params;  // p, g, m, v read; p, m, v written
  return bytes;
}

// Every step starts from the same field (Adam would otherwise train it between steps and change
// the sample counts); copied into the existing buffers, outside the timing.
void RestoreStartingField(StepBench& b) {
  std::copy(b.density0.begin(), b.density0.end(), b.model.density().params().begin());
  std::copy(b.app0.begin(), b.app0.end(), b.model.appearance().params().begin());
  std::copy(b.head0.begin(), b.head0.end(), b.model.head().params().begin());
}

// One training iteration as the trainer runs it, started at time t0: each phase's seconds in t.
TrainStepStats TimeOneStep(StepBench& b, bool rate_phase, int rays, int rep, double t0,
                           double t[kNumPhases]) {
  TensorfModel& model = b.model;
  double clock = t0;
  auto lap = [&clock]() {
    const double now = omp_get_wtime(), dt = now - clock;
    clock = now;
    return dt;
  };
  model.ZeroGrads();
  t[kZero] = lap();
  if (rate_phase) {
    b.qat.Refresh(model, b.rate.steps, b.rate.config, b.options.mlp_levels,
                  b.options.rounding_offset, b.options.rdoq_lambda);
    t[kQatRefresh] = lap();
    b.qat.Apply(&model);
    t[kQatApply] = lap();
  }
  const TrainStepStats stats =
      trainer::TrainStep(model, rays, b.o.data(), b.d.data(), b.rgb.data(), 100 + rep);
  lap();
  if (rate_phase) {
    b.qat.Restore(&model);
    t[kQatApply] += lap();
  }
  t[kMarch] = stats.t_march;
  t[kHead] = stats.t_head;
  t[kComposite] = stats.t_composite;
  t[kScatter] = stats.t_scatter;
  model.DensityL1(8e-5f);
  t[kL1] = lap();
  if (rate_phase) {
    b.rate.Step(model, b.options, 1000 + rep);
    t[kRate] = lap();
  }
  b.adam_density.Step(model.density().params().data(), model.density().grads().data(),
                      model.density().params().size(), 0.02f);
  b.adam_app.Step(model.appearance().params().data(), model.appearance().grads().data(),
                  model.appearance().params().size(), 0.02f);
  b.adam_head.Step(model.head().params().data(), model.head().grads().data(),
                   model.head().params().size(), 1e-3f);
  t[kAdam] = lap();
  return stats;
}

// What one thread count measured: the median seconds of each phase and of the whole step, the
// triad bandwidth and the FMA peak.
struct ThreadCountResult {
  std::array<double, kNumPhases> phase_medians{};
  double step_median = 0.0;
  double bandwidth = 0.0;
  double fma_peak_gflops = 0.0;
};

int RankSum(const VmGrid& grid) { return grid.ranks()[0] + grid.ranks()[1] + grid.ranks()[2]; }

// The head's and the scatter's arithmetic rate against this thread count's measured FMA peak, and
// the scatter's traffic against the triad bandwidth (work_counts.h: what each count includes).
void PrintPeakShares(const StepBench& b, const TrainStepStats& last, const ThreadCountResult& r,
                     int nthreads, BenchReport* report) {
  const MlpFlops head = HeadFlops(b.model.head().config(), b.model.head(), last.head_rows);
  const ScatterWork scatter = ScatterCounts(last.density_samples, RankSum(b.model.density()),
                                            last.appearance_samples, RankSum(b.model.appearance()));
  auto billions_per_second = [](double count, double s) {
    return s > 0.0 ? count / s * 1e-9 : 0.0;
  };
  const double head_gflops =
      billions_per_second(head.forward + head.backward, r.phase_medians[kHead]);
  const double scatter_gflops = billions_per_second(scatter.flops, r.phase_medians[kScatter]);
  const double scatter_gbs = billions_per_second(scatter.bytes, r.phase_medians[kScatter]);
  std::printf(
      "  against the measured peaks (%s FMA loop %.1f GFLOP/s, triad %.1f GB/s): head %ld rows, "
      "%.1f GFLOP/s (%.1f %%); scatter %.1f GFLOP/s (%.1f %%), %.1f GB/s of gradient entries "
      "(%.0f %% of triad)\n",
      FmaPeakIsa(), r.fma_peak_gflops, r.bandwidth / 1e9, last.head_rows, head_gflops,
      100.0 * head_gflops / r.fma_peak_gflops, scatter_gflops,
      100.0 * scatter_gflops / r.fma_peak_gflops, scatter_gbs,
      100.0 * scatter_gbs * 1e9 / r.bandwidth);
  const std::string prefix = "threads_" + std::to_string(nthreads) + "_";
  report->Record(prefix + "fma_peak_gflops", r.fma_peak_gflops);
  report->Record(prefix + "head_rows", static_cast<double>(last.head_rows));
  report->Record(prefix + "head_gflops", head_gflops);
  report->Record(prefix + "scatter_gflops", scatter_gflops);
  report->Record(prefix + "scatter_entry_gb_per_s", scatter_gbs);
}

// Times a warm-up step and `reps` steps on `nthreads` threads, prints the thread count's line
// and records its figures.
ThreadCountResult TimeThreadCount(StepBench& b, const TrainStepBenchFlags& f, int nthreads,
                                  BenchReport* report) {
  omp_set_num_threads(nthreads);
  std::vector<double> times, phase_times[kNumPhases];
  TrainStepStats last;
  double cpu = 0.0, wall = 0.0;
  for (int rep = 0; rep <= f.reps; ++rep) {
    RestoreStartingField(b);
    double t[kNumPhases] = {};
    const double t0 = omp_get_wtime(), c0 = CpuSeconds();
    last = TimeOneStep(b, f.rate_phase, f.rays, rep, t0, t);
    const double dt = omp_get_wtime() - t0;
    if (rep > 0) {
      times.push_back(dt);
      for (int k = 0; k < kNumPhases; ++k) phase_times[k].push_back(t[k]);
      cpu += CpuSeconds() - c0;
      wall += dt;
    }
  }
  ThreadCountResult r;
  for (int k = 0; k < kNumPhases; ++k) r.phase_medians[k] = Median(phase_times[k]);
  r.step_median = Median(times);
  r.bandwidth = MeasureTriadBandwidth(nthreads);
  r.fma_peak_gflops = MeasureFmaPeakGflops(nthreads);
  std::sort(times.begin(), times.end());
  // cpu / (threads * wall) < 1 means other processes competed for the cores.
  std::printf(
      "threads %d: median %.3f s (min %.3f), cpu/(threads*wall) %.2f | density samples %ld, "
      "appearance samples %ld | scatter tasks %d | triad bandwidth %.1f GB/s | peak RSS %.0f "
      "MB\n",
      nthreads, r.step_median, times[0], cpu / (nthreads * wall), last.density_samples,
      last.appearance_samples, trainer::ScatterTaskCount(b.model), r.bandwidth / 1e9, PeakRssMb());
  const std::string prefix = "threads_" + std::to_string(nthreads) + "_";
  report->Record(prefix + "step_median", r.step_median);
  for (int k = 0; k < kNumPhases; ++k) report->Record(prefix + kPhaseKeys[k], r.phase_medians[k]);
  report->Record(prefix + "triad_gb_per_s", r.bandwidth / 1e9);
  PrintPeakShares(b, last, r, nthreads, report);
  return r;
}

// The thread counts the scaling table predicts.
constexpr std::array<int, 4> kPredictedThreads = {8, 16, 32, 64};

// The scaling table: measured medians, the fitted serial fraction, predictions (each recorded).
void PrintScalingTable(const std::vector<int>& thread_counts,
                       const std::vector<ThreadCountResult>& results,
                       const std::array<double, kNumPhases>& phase_bytes, int scatter_tasks,
                       BenchReport* report) {
  double bandwidth = 0.0;
  for (const ThreadCountResult& r : results) bandwidth = std::max(bandwidth, r.bandwidth);
  std::printf(
      "\nscaling table (median seconds per step; prediction = Amdahl fit over the measured "
      "counts, capped by the phase's tasks, floored by its bytes over %.1f GB/s, the best "
      "triad bandwidth measured here):\n%-12s",
      bandwidth / 1e9, "phase");
  for (int n : thread_counts) std::printf(" %8s", (std::to_string(n) + " thr").c_str());
  std::printf(" %7s %6s", "serial", "MB");
  for (int n : kPredictedThreads) std::printf(" %16s", ("pred " + std::to_string(n)).c_str());
  std::printf("\n");
  std::array<double, kPredictedThreads.size()> total_pred{};
  for (int k = 0; k < kNumPhases; ++k) {
    std::vector<double> col;
    for (const ThreadCountResult& r : results) col.push_back(r.phase_medians[k]);
    if (col[0] == 0.0 && col.back() == 0.0) continue;  // a phase this run skips
    std::printf("%-12s", kPhaseNames[k]);
    for (double v : col) std::printf(" %8.4f", v);
    PhaseModel pm;
    pm.serial = FitSerialFraction(thread_counts, col);
    pm.bytes = phase_bytes[k];
    for (size_t i = 0; i < thread_counts.size(); ++i)
      if (thread_counts[i] == 1) pm.t1 = col[i];
    if (pm.serial < 0.0 || pm.t1 <= 0.0) {
      std::printf("   (measure 1 thread and more to fit)\n");
      continue;
    }
    std::printf(" %7.3f %6.0f", pm.serial, pm.bytes / 1e6);
    const int tasks = k == kScatter ? scatter_tasks : 0;
    for (size_t j = 0; j < kPredictedThreads.size(); ++j) {
      const Prediction p = PredictPhase(pm, kPredictedThreads[j], tasks, bandwidth);
      total_pred[j] += p.seconds;
      std::printf(" %7.4f %-8s", p.seconds, p.bound.c_str());
      report->Record("predicted_" + std::to_string(kPredictedThreads[j]) + "_" + kPhaseKeys[k],
                     p.seconds);
    }
    std::printf("\n");
  }
  std::printf("%-12s", "step");
  for (const ThreadCountResult& r : results) std::printf(" %8.4f", r.step_median);
  std::printf(" %7s %6s", "", "");
  for (double seconds : total_pred) std::printf(" %16.4f", seconds);
  std::printf("\n");
  for (size_t j = 0; j < kPredictedThreads.size(); ++j)
    report->Record("predicted_" + std::to_string(kPredictedThreads[j]) + "_step", total_pred[j]);
}

}  // namespace

int RunTrainStepBench(int argc, char** argv) {
  TrainStepBenchFlags f;
  auto app = MakeCommand(
      "bench train",
      "times one training iteration as the trainer runs it in its rate phase, phase by phase "
      "(zero the gradients, quantization-aware refresh and apply, march, head, composite, "
      "scatter, density L1, rate term, Adam) on a synthetic Blender-like scene (an opaque soft "
      "blob in a randomly initialised VM-192 field) at each thread count, then the scaling "
      "table: serial fraction and predicted times at 8-64 threads per phase");
  AddTrainStepBenchFlags(app.get(), &f);
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  const std::vector<int> thread_counts = ThreadCounts(f.threads);
  StepBench bench(f);
  const TensorfModel& model = bench.model;
  const trainer::TensorfConfig& c = model.config();
  std::printf(
      "train-step bench: %s, grid %dx%dx%d, %d rays, %d samples/ray, mask %s, early stop %g, %s "
      "head (%d hidden layers), %s (lambda_e %g), rdoq %g\n",
      f.run.empty() ? ("blob, res " + std::to_string(f.res) + "^3").c_str() : f.run.c_str(),
      model.res()[0], model.res()[1], model.res()[2], f.rays, model.n_samples(),
      model.alpha_mask() ? "yes" : "no", c.early_stop_transmittance,
      kHeadKindNames[static_cast<int>(c.head.kind)], c.head.hidden_layers,
      f.rate_phase ? "rate phase, quantization-aware" : "plain TensoRF",
      f.rate_phase ? bench.options.lambda_e : 0.f, bench.options.rdoq_lambda);
  const std::array<double, kNumPhases> phase_bytes = PhaseBytes(model, f.rate_phase);
  std::vector<ThreadCountResult> results;
  BenchReport report;
  for (int nthreads : thread_counts)
    results.push_back(TimeThreadCount(bench, f, nthreads, &report));
  PrintScalingTable(thread_counts, results, phase_bytes, trainer::ScatterTaskCount(model), &report);
  if (!f.json_path.empty() && !report.WriteJson(f.json_path)) {
    std::fprintf(stderr, "bench train: cannot write %s\n", f.json_path.c_str());
    return 1;
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
