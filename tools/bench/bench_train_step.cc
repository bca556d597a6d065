// `ecrf bench train`: times one training iteration as the trainer runs it in its rate phase,
// phase by phase (zero the gradients, quantization-aware refresh and apply, TrainStep = march,
// head, composite and scatter, density L1, the rate term, Adam on grids and head) on a synthetic
// Blender-like scene: aabb [-1.5,1.5]^3, cameras on a sphere of radius 4, an opaque soft blob in
// the middle of a randomly initialised VM-192 field, at each thread count asked for. It then
// prints the scaling table: per phase the measured times, the fitted serial fraction and the
// predicted times at 8-64 threads with what bounds each (scaling_model.h), so the same command
// gives the figure on any machine. Flags and their defaults: `ecrf bench train --help`.
#include <omp.h>
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "tools/bench/bench_json.h"
#include "tools/bench/scaling_model.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/quant_aware.h"
#include "trainer/train/adam.h"
#include "trainer/train/rate_state.h"
#include "trainer/train/train_options.h"

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

}  // namespace

int RunTrainStepBench(int argc, char** argv) {
  int res = 128, rays = 4096, reps = 5, mask = 0, rate_phase = 1;
  float early = 0.f, blob_peak = 14.f, rdoq = 0.f;
  std::string threads = "1,2", json_path;
  auto app = MakeCommand(
      "bench train",
      "times one training iteration as the trainer runs it in its rate phase, phase by phase "
      "(zero the gradients, quantization-aware refresh and apply, march, head, composite, "
      "scatter, density L1, rate term, Adam) on a synthetic Blender-like scene (an opaque soft "
      "blob in a randomly initialised VM-192 field) at each thread count, then the scaling "
      "table: serial fraction and predicted times at 8-64 threads per phase");
  app->add_option("--res", res, "grid resolution per axis")
      ->type_name("N")
      ->check(CLI::Range(2, 1024))
      ->capture_default_str();
  app->add_option("--rays", rays, "rays per batch")
      ->type_name("N")
      ->check(CLI::Range(1, 1 << 24))
      ->capture_default_str();
  app->add_option("--reps", reps, "timed steps per thread count (after one warm-up step)")
      ->type_name("N")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  AddThreadListFlag(app.get(), &threads);
  app->add_option("--mask", mask, "update the alpha mask (and shrink) before timing (0: no mask)")
      ->type_name("0|1")
      ->check(CLI::Range(0, 1))
      ->capture_default_str();
  app->add_option("--rate", rate_phase,
                  "1: the rate phase's iteration (rate term at the medium point's lambda_e, "
                  "quantization-aware training); 0: plain TensoRF's")
      ->type_name("0|1")
      ->check(CLI::Range(0, 1))
      ->capture_default_str();
  app->add_option("--rdoq", rdoq,
                  "the rate phase's quantizer: RDOQ with this lambda (0: rounding), as ecrf train "
                  "--rdoq")
      ->type_name("L")
      ->check(CLI::Range(0.0f, 10.0f))
      ->capture_default_str();
  app->add_option("--early-stop", early, "early_stop_transmittance of the ray marching")
      ->type_name("T")
      ->check(CLI::Range(0.0f, 1.0f))
      ->capture_default_str();
  app->add_option(
         "--blob-peak", blob_peak,
         "peak density feature of the blob; larger -> more opaque -> fewer appearance samples per "
         "ray "
         "(e.g. 40 gives about the 0.14 M of the reference PyTorch run's iterations 150-320)")
      ->type_name("F")
      ->check(CLI::Range(0.0f, 1000.0f))
      ->capture_default_str();
  app->add_option("--json", json_path,
                  "also write the figures (per phase and thread count, and the predictions) as "
                  "JSON")
      ->type_name("FILE");
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  const std::vector<int> thread_counts = ThreadCounts(threads);

  TensorfConfig config;
  config.early_stop_transmittance = early;
  TensorfModel model(config);
  model.Initialize({res, res, res}, 1);
  AddBlob(model, blob_peak);  // feature up to blob_peak: sigma up to softplus(peak - 10)
  if (mask) {
    const trainer::Aabb box = model.UpdateAlphaMask({res, res, res});
    model.Shrink(box);
  }
  std::vector<float> o, d, rgb;
  MakeRays(rays, 7, &o, &d, &rgb);
  std::printf(
      "train-step bench: res %d^3 (after shrink %dx%dx%d), %d rays, %d samples/ray, mask %d, "
      "early stop %g, blob peak %g, %s, rdoq %g\n",
      res, model.res()[0], model.res()[1], model.res()[2], rays, model.n_samples(), mask, early,
      blob_peak, rate_phase ? "rate phase (lambda_e 3e-11, quantization-aware)" : "plain TensoRF",
      rdoq);
  // The trainer's optimizers (trainer.cc): grids at lr 0.02, head at 1e-3.
  trainer::Adam adam_density(model.density().params().size(), trainer::AdamConfig{});
  trainer::Adam adam_app(model.appearance().params().size(), trainer::AdamConfig{});
  trainer::Adam adam_head(model.head().params().size(), trainer::AdamConfig{});
  trainer::TrainOptions options;
  options.lambda_e = 3e-11f;  // the medium rate point's
  options.rdoq_lambda = rdoq;
  trainer::RateState rate;
  trainer::QuantAwareModel qat;
  if (rate_phase) rate.Activate(model, options);
  const std::vector<float> density0 = model.density().params(), app0 = model.appearance().params(),
                           head0 = model.head().params();
  const double grid_params =
      static_cast<double>(model.density().params().size() + model.appearance().params().size());
  const double all_params = grid_params + static_cast<double>(model.head().params().size());
  // Bytes each streaming phase reads and writes per step (the memory-bandwidth floor).
  double phase_bytes[kNumPhases] = {};
  phase_bytes[kZero] = 4.0 * all_params;
  phase_bytes[kQatApply] = rate_phase ? 12.0 * all_params : 0.0;
  phase_bytes[kL1] = 12.0 * static_cast<double>(model.density().params().size());
  phase_bytes[kAdam] = 28.0 * all_params;  // p, g, m, v read; p, m, v written

  std::vector<std::array<double, kNumPhases>> medians;
  std::vector<double> step_medians, bandwidths;
  BenchReport report;
  for (int nthreads : thread_counts) {
    omp_set_num_threads(nthreads);
    std::vector<double> times, phase_times[kNumPhases];
    TrainStepStats last;
    double cpu = 0.0, wall = 0.0;
    for (int rep = 0; rep <= reps; ++rep) {
      // Every step starts from the same field (Adam would otherwise train it between steps and
      // change the sample counts); copied into the existing buffers, outside the timing.
      std::copy(density0.begin(), density0.end(), model.density().params().begin());
      std::copy(app0.begin(), app0.end(), model.appearance().params().begin());
      std::copy(head0.begin(), head0.end(), model.head().params().begin());
      double t[kNumPhases] = {};
      const double t0 = omp_get_wtime(), c0 = CpuSeconds();
      double clock = t0;
      auto lap = [&clock]() {
        const double now = omp_get_wtime(), dt = now - clock;
        clock = now;
        return dt;
      };
      model.ZeroGrads();
      t[kZero] = lap();
      if (rate_phase) {
        qat.Refresh(model, rate.steps, rate.config, options.mlp_levels, options.rounding_offset,
                    options.rdoq_lambda);
        t[kQatRefresh] = lap();
        qat.Apply(&model);
        t[kQatApply] = lap();
      }
      last = trainer::TrainStep(model, rays, o.data(), d.data(), rgb.data(), 100 + rep);
      lap();
      if (rate_phase) {
        qat.Restore(&model);
        t[kQatApply] += lap();
      }
      t[kMarch] = last.t_march;
      t[kHead] = last.t_head;
      t[kComposite] = last.t_composite;
      t[kScatter] = last.t_scatter;
      model.DensityL1(8e-5f);
      t[kL1] = lap();
      if (rate_phase) {
        rate.Step(model, options, 1000 + rep);
        t[kRate] = lap();
      }
      adam_density.Step(model.density().params().data(), model.density().grads().data(),
                        model.density().params().size(), 0.02f);
      adam_app.Step(model.appearance().params().data(), model.appearance().grads().data(),
                    model.appearance().params().size(), 0.02f);
      adam_head.Step(model.head().params().data(), model.head().grads().data(),
                     model.head().params().size(), 1e-3f);
      t[kAdam] = lap();
      const double dt = omp_get_wtime() - t0;
      if (rep > 0) {
        times.push_back(dt);
        for (int k = 0; k < kNumPhases; ++k) phase_times[k].push_back(t[k]);
        cpu += CpuSeconds() - c0;
        wall += dt;
      }
    }
    std::array<double, kNumPhases> med{};
    for (int k = 0; k < kNumPhases; ++k) med[k] = Median(phase_times[k]);
    medians.push_back(med);
    step_medians.push_back(Median(times));
    bandwidths.push_back(MeasureTriadBandwidth(nthreads));
    std::sort(times.begin(), times.end());
    // cpu / (threads * wall) < 1 means other processes competed for the cores.
    std::printf(
        "threads %d: median %.3f s (min %.3f), cpu/(threads*wall) %.2f | density samples %ld, "
        "appearance samples %ld | scatter tasks %d | triad bandwidth %.1f GB/s | peak RSS %.0f "
        "MB\n",
        nthreads, step_medians.back(), times[0], cpu / (nthreads * wall), last.density_samples,
        last.appearance_samples, trainer::ScatterTaskCount(model), bandwidths.back() / 1e9,
        PeakRssMb());
    report.Record("threads_" + std::to_string(nthreads) + "_step_median", step_medians.back());
    for (int k = 0; k < kNumPhases; ++k)
      report.Record("threads_" + std::to_string(nthreads) + "_" + kPhaseKeys[k], med[k]);
    report.Record("threads_" + std::to_string(nthreads) + "_triad_gb_per_s",
                  bandwidths.back() / 1e9);
  }

  // The scaling table: measured medians, the fitted serial fraction, predictions.
  const std::vector<int> predicted = {8, 16, 32, 64};
  const double bandwidth = *std::max_element(bandwidths.begin(), bandwidths.end());
  std::printf(
      "\nscaling table (median seconds per step; prediction = Amdahl fit over the measured "
      "counts, capped by the phase's tasks, floored by its bytes over %.1f GB/s, the best "
      "triad bandwidth measured here):\n%-12s",
      bandwidth / 1e9, "phase");
  for (int n : thread_counts) std::printf(" %8s", (std::to_string(n) + " thr").c_str());
  std::printf(" %7s %6s", "serial", "MB");
  for (int n : predicted) std::printf(" %16s", ("pred " + std::to_string(n)).c_str());
  std::printf("\n");
  double total_pred[4] = {};
  for (int k = 0; k < kNumPhases; ++k) {
    std::vector<double> col;
    for (const auto& med : medians) col.push_back(med[k]);
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
    const int tasks = k == kScatter ? trainer::ScatterTaskCount(model) : 0;
    for (int j = 0; j < 4; ++j) {
      const Prediction p = PredictPhase(pm, predicted[j], tasks, bandwidth);
      total_pred[j] += p.seconds;
      std::printf(" %7.4f %-8s", p.seconds, p.bound.c_str());
      report.Record("predicted_" + std::to_string(predicted[j]) + "_" + kPhaseKeys[k], p.seconds);
    }
    std::printf("\n");
  }
  std::printf("%-12s", "step");
  for (double v : step_medians) std::printf(" %8.4f", v);
  std::printf(" %7s %6s", "", "");
  for (int j = 0; j < 4; ++j) std::printf(" %16.4f", total_pred[j]);
  std::printf("\n");
  for (int j = 0; j < 4; ++j)
    report.Record("predicted_" + std::to_string(predicted[j]) + "_step", total_pred[j]);
  if (!json_path.empty() && !report.WriteJson(json_path)) {
    std::fprintf(stderr, "bench train: cannot write %s\n", json_path.c_str());
    return 1;
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
