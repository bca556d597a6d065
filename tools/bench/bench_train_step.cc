// `ecrf bench train`: times one training iteration as the trainer runs it (zero the gradients,
// TrainStep = forward + backward incl. the appearance head, density L1, Adam on grids and head)
// on a synthetic Blender-like scene: aabb [-1.5,1.5]^3, cameras on a sphere of radius 4, an
// opaque soft blob in the middle of a randomly initialised VM-192 field. Flags and their
// defaults: `ecrf bench train --help`.
#include <omp.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "tools/bench/bench_json.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/model/volume_render.h"
#include "trainer/train/adam.h"

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

}  // namespace

int RunTrainStepBench(int argc, char** argv) {
  int res = 128, rays = 4096, reps = 5, mask = 0;
  float early = 0.f, blob_peak = 14.f;
  std::string threads = "1,2", json_path;
  auto app = MakeCommand(
      "bench train",
      "times one training iteration as the trainer runs it (zero the gradients, forward + "
      "backward incl. the appearance head, density L1, Adam on grids and head) on a synthetic "
      "Blender-like scene: an opaque soft blob in a randomly initialised VM-192 field");
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
  app->add_option("--json", json_path, "also write the figures of the last thread count as JSON")
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
      "early stop %g, blob peak %g\n",
      res, model.res()[0], model.res()[1], model.res()[2], rays, model.n_samples(), mask, early,
      blob_peak);
  // The trainer's optimizers (trainer.cc): grids at lr 0.02, head at 1e-3.
  trainer::Adam adam_density(model.density().params().size(), trainer::AdamConfig{});
  trainer::Adam adam_app(model.appearance().params().size(), trainer::AdamConfig{});
  trainer::Adam adam_head(model.head().params().size(), trainer::AdamConfig{});
  const std::vector<float> density0 = model.density().params(), app0 = model.appearance().params(),
                           head0 = model.head().params();
  BenchReport report;
  for (int threads : thread_counts) {
    omp_set_num_threads(threads);
    std::vector<double> times;
    TrainStepStats last;
    double cpu = 0.0, wall = 0.0, t_optim = 0.0;
    for (int rep = 0; rep <= reps; ++rep) {
      // Every step starts from the same field (Adam would otherwise train it between steps and
      // change the sample counts); copied into the existing buffers, outside the timing.
      std::copy(density0.begin(), density0.end(), model.density().params().begin());
      std::copy(app0.begin(), app0.end(), model.appearance().params().begin());
      std::copy(head0.begin(), head0.end(), model.head().params().begin());
      const double t0 = omp_get_wtime(), c0 = CpuSeconds();
      model.ZeroGrads();
      last = trainer::TrainStep(model, rays, o.data(), d.data(), rgb.data(), 100 + rep);
      const double t1 = omp_get_wtime();
      model.DensityL1(8e-5f);
      adam_density.Step(model.density().params().data(), model.density().grads().data(),
                        model.density().params().size(), 0.02f);
      adam_app.Step(model.appearance().params().data(), model.appearance().grads().data(),
                    model.appearance().params().size(), 0.02f);
      adam_head.Step(model.head().params().data(), model.head().grads().data(),
                     model.head().params().size(), 1e-3f);
      const double dt = omp_get_wtime() - t0;
      if (rep > 0) {
        times.push_back(dt);
        cpu += CpuSeconds() - c0;
        wall += dt;
        t_optim = omp_get_wtime() - t1;
      }
    }
    std::sort(times.begin(), times.end());
    const double median = times[times.size() / 2];
    // cpu / (threads * wall) < 1 means other processes competed for the cores.
    std::printf(
        "threads %d: median %.3f s (min %.3f), cpu/(threads*wall) %.2f | density samples %ld, "
        "appearance samples %ld | last step: march %.3f head %.3f composite %.3f scatter %.3f "
        "L1+adam %.3f | peak RSS %.0f MB\n",
        threads, median, times[0], cpu / (threads * wall), last.density_samples,
        last.appearance_samples, last.t_march, last.t_head, last.t_composite, last.t_scatter,
        t_optim, PeakRssMb());
    if (threads == thread_counts.back()) {
      report.Add("threads", threads, "");
      report.Add("step_median", median, "s");
      report.Add("step_min", times[0], "s");
      report.Add("density_samples", static_cast<double>(last.density_samples), "");
      report.Add("appearance_samples", static_cast<double>(last.appearance_samples), "");
      report.Add("march", last.t_march, "s");
      report.Add("head", last.t_head, "s");
      report.Add("composite", last.t_composite, "s");
      report.Add("scatter", last.t_scatter, "s");
      report.Add("l1_adam", t_optim, "s");
      report.Add("peak_rss", PeakRssMb(), "MB");
    }
  }
  if (!json_path.empty() && !report.WriteJson(json_path)) {
    std::fprintf(stderr, "bench train: cannot write %s\n", json_path.c_str());
    return 1;
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
