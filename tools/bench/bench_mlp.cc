// `ecrf bench mlp`: throughput of the appearance MLP (AppearanceHead, on SmallGemm) and Adam
// against this CPU's measured single-precision FMA peak, with Eigen's GEMM on the shape of the
// first MLP layer for comparison. Times are medians of --reps runs, or the fastest run with
// --best; flags and their defaults: `ecrf bench mlp --help`.
#include <omp.h>

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "decoder/mlp.h"
#include "tools/bench/bench_json.h"
#include "tools/bench/cpu_peak.h"
#include "tools/bench/work_counts.h"
#include "trainer/data/file_io.h"
#include "trainer/model/appearance_head.h"
#include "trainer/model/small_gemm.h"
#include "trainer/train/adam.h"

namespace ecrf {
namespace tools {

int RunMlpBench(int argc, char** argv);

namespace {

using Clock = std::chrono::steady_clock;
using RowMat = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Seconds of `reps` runs of f (after one warm-up run): the median, or with --best the fastest
// (steadier on a machine shared with other jobs).
bool g_use_best = false;
template <typename F>
double MedianSeconds(int reps, F&& f) {
  f();
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = Clock::now();
    f();
    t.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  return g_use_best ? t.front() : t[t.size() / 2];
}

// The settings of `ecrf bench mlp`, as its command line gives them (--best sets g_use_best).
struct MlpBenchFlags {
  int n = 131072, reps = 5, chunk = 256;
  long adam_size = 20000000;
  std::string threads = "1," + std::to_string(std::max(1, omp_get_max_threads())), json_path;
};

void AddMlpBenchFlags(CLI::App* app, MlpBenchFlags* f) {
  app->add_option("--n", f->n, "rows (samples) per forward/backward")
      ->type_name("N")
      ->check(CLI::Range(1, 1 << 26))
      ->capture_default_str();
  AddThreadListFlag(app, &f->threads);
  app->add_option("--reps", f->reps, "timed runs per figure (after one warm-up run)")
      ->type_name("R")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app->add_option("--chunk", f->chunk, "the head's rows per chunk (at least 16 are used)")
      ->type_name("ROWS")
      ->check(CLI::Range(1, 1 << 26))
      ->capture_default_str();
  app->add_option("--adam", f->adam_size,
                  "parameters of the Adam step measured (0 = no Adam figure)")
      ->type_name("FLOATS")
      ->check(CLI::Range(0L, 1L << 32))
      ->capture_default_str();
  app->add_flag("--best", g_use_best,
                "report the fastest run instead of the median (steadier on a shared machine)");
  app->add_option("--json", f->json_path, "also write the figures as JSON")->type_name("FILE");
}

// The rows the MLPs run on: random products, unit view directions (off the z = 0 plane) and the
// gradients that come back from the colours; rgb and dl_dproducts are the outputs.
struct MlpRows {
  std::vector<float> products, viewdirs, rgb, dl_drgb, dl_dproducts;
};

MlpRows MakeMlpRows(int n, int P) {
  std::mt19937 rng(1);
  std::normal_distribution<float> normal(0.0f, 0.3f);
  MlpRows rows;
  rows.products.resize(static_cast<size_t>(n) * P);
  rows.viewdirs.resize(3 * static_cast<size_t>(n));
  for (float& v : rows.products) v = normal(rng);
  for (int i = 0; i < n; ++i) {
    float d[3] = {normal(rng), normal(rng), normal(rng) + 0.01f};
    const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int c = 0; c < 3; ++c) rows.viewdirs[3 * i + c] = d[c] / len;
  }
  rows.rgb.resize(3 * static_cast<size_t>(n));
  rows.dl_drgb.resize(rows.rgb.size());
  rows.dl_dproducts.resize(rows.products.size());
  for (float& v : rows.dl_drgb) v = normal(rng);
  return rows;
}

// The decoder's MLP (decoder/mlp.h: separate multiplies and adds, SPEC.md 7.6) on the head's
// weights; false when it refuses them.
bool InitDecoderMlp(const trainer::AppearanceHeadConfig& cfg, const trainer::AppearanceHead& head,
                    dec::AppearanceMlp* mlp) {
  dec::MlpConfig dcfg;
  dcfg.num_products = cfg.num_products;
  dcfg.feature_dim = cfg.feature_dim;
  dcfg.feature_pe_freqs = cfg.feature_pe_freqs;
  dcfg.viewdir_pe_freqs = cfg.viewdir_pe_freqs;
  dcfg.hidden = cfg.hidden;
  return mlp->Init(dcfg).ok() && mlp->SetParams(head.params().data(), head.params().size()).ok();
}

// The shape of the first MLP layer, on which Eigen's GEMM is timed for comparison.
const int kGemmM = 4096, kGemmK = 150, kGemmN = 128;

// What one thread count measured.
struct MlpTimes {
  double peak_gflops = 0.0, gemm_gflops = 0.0;
  double forward_s = 0.0, backward_s = 0.0, infer_s = 0.0, decoder_s = 0.0, adam_s = 0.0;
};

// Eigen's GEMM (its own threading) on the shape of the first MLP layer.
double EigenGemmGflops(int reps) {
  RowMat a = RowMat::Random(kGemmM, kGemmK), b = RowMat::Random(kGemmK, kGemmN), c(kGemmM, kGemmN);
  const double gemm_s = MedianSeconds(std::max(reps, 20), [&] { c.noalias() = a * b; });
  return 2.0 * kGemmM * kGemmK * kGemmN / gemm_s * 1e-9;
}

// The decoder's MLP, each thread on its share of the rows.
double DecoderInferSeconds(const dec::AppearanceMlp& mlp, MlpRows* rows, int n, int P, int threads,
                           int reps) {
  std::vector<std::vector<float>> scratch(threads, std::vector<float>(mlp.ScratchFloats()));
  return MedianSeconds(reps, [&] {
#pragma omp parallel num_threads(threads)
    {
      const int t = omp_get_thread_num(), nt = omp_get_num_threads();
      const int r0 = int(long(n) * t / nt), r1 = int(long(n) * (t + 1) / nt);
      mlp.Infer(r1 - r0, rows->products.data() + size_t(r0) * P, P,
                rows->viewdirs.data() + size_t(r0) * 3, rows->rgb.data() + size_t(r0) * 3,
                scratch[t].data());
    }
  });
}

double AdamSeconds(long size, int reps) {
  std::vector<float> p(static_cast<size_t>(size), 0.5f), g(p.size(), 0.25f);
  trainer::Adam adam(p.size(), trainer::AdamConfig{});
  return MedianSeconds(reps, [&] { adam.Step(p.data(), g.data(), p.size(), 1e-3f); });
}

MlpTimes TimeMlps(trainer::AppearanceHead& head, const dec::AppearanceMlp& decoder_mlp,
                  MlpRows* rows, const MlpBenchFlags& f, int threads) {
  MlpTimes t;
  t.peak_gflops = MeasureFmaPeakGflops(threads);
  Eigen::setNbThreads(threads);
  omp_set_num_threads(threads);
  t.gemm_gflops = EigenGemmGflops(f.reps);
  const int n = f.n;
  t.forward_s = MedianSeconds(f.reps, [&] {
    head.Forward(n, rows->products.data(), rows->viewdirs.data(), rows->rgb.data());
  });
  head.Forward(n, rows->products.data(), rows->viewdirs.data(), rows->rgb.data());
  t.backward_s = MedianSeconds(
      f.reps, [&] { head.Backward(n, rows->dl_drgb.data(), rows->dl_dproducts.data()); });
  t.infer_s = MedianSeconds(f.reps, [&] {
    head.Infer(n, rows->products.data(), rows->viewdirs.data(), rows->rgb.data());
  });
  t.decoder_s =
      DecoderInferSeconds(decoder_mlp, rows, n, head.config().num_products, threads, f.reps);
  if (f.adam_size > 0) t.adam_s = AdamSeconds(f.adam_size, f.reps);
  return t;
}

// The decoder's figure counts every term, also those it skips (inputs that are zero after a
// ReLU): a dense-equivalent rate.
void PrintMlpTimes(int threads, const MlpTimes& t, const MlpFlops& flops, long adam_size,
                   const dec::AppearanceMlp& decoder_mlp) {
  const double peak = t.peak_gflops;
  std::printf("threads=%d  FMA peak %.1f GFLOP/s; Eigen GEMM %dx%dx%d %.1f GFLOP/s (%.0f%%)\n",
              threads, peak, kGemmM, kGemmK, kGemmN, t.gemm_gflops, 100.0 * t.gemm_gflops / peak);
  std::printf("  forward  %8.2f ms  %6.1f GFLOP/s (%.0f%% of peak)\n", t.forward_s * 1e3,
              flops.forward / t.forward_s * 1e-9,
              100.0 * flops.forward / t.forward_s * 1e-9 / peak);
  std::printf("  backward %8.2f ms  %6.1f GFLOP/s (%.0f%% of peak)\n", t.backward_s * 1e3,
              flops.backward / t.backward_s * 1e-9,
              100.0 * flops.backward / t.backward_s * 1e-9 / peak);
  std::printf("  infer    %8.2f ms  %6.1f GFLOP/s (%.0f%% of peak)\n", t.infer_s * 1e3,
              flops.forward / t.infer_s * 1e-9, 100.0 * flops.forward / t.infer_s * 1e-9 / peak);
  std::printf(
      "  decoder  %8.2f ms  %6.1f GFLOP/s (%.0f%% of the non-FMA peak %.1f; %s kernel, "
      "separate multiplies and adds)\n",
      t.decoder_s * 1e3, flops.forward / t.decoder_s * 1e-9,
      100.0 * flops.forward / t.decoder_s * 1e-9 / (peak / 2), peak / 2,
      dec::GemmKernelName(decoder_mlp.gemm_kernel()));
  if (adam_size > 0) {
    std::printf("  adam     %8.2f ms for %ld floats (%.1f GB/s of 7 streams)\n", t.adam_s * 1e3,
                adam_size, 7.0 * 4 * adam_size / t.adam_s * 1e-9);
  }
}

nlohmann::json MlpTimesJson(const MlpTimes& t, const MlpFlops& flops, long adam_size) {
  nlohmann::json r;
  r["fma_peak_gflops"] = t.peak_gflops;
  r["eigen_gemm_gflops"] = t.gemm_gflops;
  r["forward_ms"] = t.forward_s * 1e3;
  r["forward_gflops"] = flops.forward / t.forward_s * 1e-9;
  r["backward_ms"] = t.backward_s * 1e3;
  r["backward_gflops"] = flops.backward / t.backward_s * 1e-9;
  r["infer_ms"] = t.infer_s * 1e3;
  r["infer_gflops"] = flops.forward / t.infer_s * 1e-9;
  r["decoder_infer_ms"] = t.decoder_s * 1e3;
  r["decoder_infer_gflops"] = flops.forward / t.decoder_s * 1e-9;
  if (adam_size > 0) r["adam_ms"] = t.adam_s * 1e3;
  return r;
}

}  // namespace

int RunMlpBench(int argc, char** argv) {
  MlpBenchFlags f;
  auto app = MakeCommand(
      "bench mlp",
      "throughput of the appearance MLP (AppearanceHead, on SmallGemm) and Adam against this "
      "CPU's measured single-precision FMA peak, with Eigen's GEMM on the shape of the first MLP "
      "layer for comparison; times are medians of --reps runs, or the fastest with --best");
  AddMlpBenchFlags(app.get(), &f);
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  const std::vector<int> thread_counts = ThreadCounts(f.threads);
  const int saved_threads = omp_get_max_threads();
  const int saved_eigen_threads = Eigen::nbThreads();

  trainer::AppearanceHeadConfig cfg;
  trainer::AppearanceHead head(cfg);
  head.Initialize(1);
  head.set_chunk_rows(f.chunk);
  const MlpFlops flops = HeadFlops(cfg, head, f.n);
  MlpRows rows = MakeMlpRows(f.n, cfg.num_products);
  dec::AppearanceMlp decoder_mlp;
  if (!InitDecoderMlp(cfg, head, &decoder_mlp)) {
    std::fprintf(stderr, "bench mlp: the decoder MLP refused the head's parameters\n");
    return 1;
  }

  nlohmann::json report;
  report["n"] = f.n;
  report["chunk_rows"] = f.chunk;
  report["statistic"] = g_use_best ? "min" : "median";
  report["eigen_simd"] = Eigen::SimdInstructionSetsInUse();
  report["small_gemm_isa"] = trainer::SmallGemmIsa();
  report["fma_peak_isa"] = FmaPeakIsa();
  std::printf("bench mlp: n=%d, chunk=%d rows, SmallGemm: %s, FMA peak loop: %s, Eigen SIMD: %s\n",
              f.n, f.chunk, trainer::SmallGemmIsa(), FmaPeakIsa(),
              Eigen::SimdInstructionSetsInUse());
  for (int threads : thread_counts) {
    const MlpTimes t = TimeMlps(head, decoder_mlp, &rows, f, threads);
    PrintMlpTimes(threads, t, flops, f.adam_size, decoder_mlp);
    report["threads"][std::to_string(threads)] = MlpTimesJson(t, flops, f.adam_size);
  }
  omp_set_num_threads(saved_threads);
  Eigen::setNbThreads(saved_eigen_threads);
  if (!f.json_path.empty()) {
    try {
      trainer::WriteFileAtomically(f.json_path, report.dump(2) + "\n");
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench mlp: %s\n", e.what());
      return 1;
    }
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
