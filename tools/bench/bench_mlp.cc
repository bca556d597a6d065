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

}  // namespace

int RunMlpBench(int argc, char** argv) {
  int n = 131072, reps = 5, chunk = 256;
  long adam_size = 20000000;
  std::string threads = "1," + std::to_string(std::max(1, omp_get_max_threads())), json_path;
  auto app = MakeCommand(
      "bench mlp",
      "throughput of the appearance MLP (AppearanceHead, on SmallGemm) and Adam against this "
      "CPU's measured single-precision FMA peak, with Eigen's GEMM on the shape of the first MLP "
      "layer for comparison; times are medians of --reps runs, or the fastest with --best");
  app->add_option("--n", n, "rows (samples) per forward/backward")
      ->type_name("N")
      ->check(CLI::Range(1, 1 << 26))
      ->capture_default_str();
  AddThreadListFlag(app.get(), &threads);
  app->add_option("--reps", reps, "timed runs per figure (after one warm-up run)")
      ->type_name("R")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app->add_option("--chunk", chunk, "the head's rows per chunk (at least 16 are used)")
      ->type_name("ROWS")
      ->check(CLI::Range(1, 1 << 26))
      ->capture_default_str();
  app->add_option("--adam", adam_size, "parameters of the Adam step measured (0 = no Adam figure)")
      ->type_name("FLOATS")
      ->check(CLI::Range(0L, 1L << 32))
      ->capture_default_str();
  app->add_flag("--best", g_use_best,
                "report the fastest run instead of the median (steadier on a shared machine)");
  app->add_option("--json", json_path, "also write the figures as JSON")->type_name("FILE");
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  const std::vector<int> thread_counts = ThreadCounts(threads);
  const int saved_threads = omp_get_max_threads();
  const int saved_eigen_threads = Eigen::nbThreads();

  trainer::AppearanceHeadConfig cfg;
  trainer::AppearanceHead head(cfg);
  head.Initialize(1);
  head.set_chunk_rows(chunk);
  const int P = cfg.num_products, F = cfg.feature_dim, H = cfg.hidden, in = head.mlp_input_dim();
  const double fwd_flops = 2.0 * n * (double(P) * F + double(in) * H + double(H) * H + H * 3.0);
  // Backward computes dL/dx only for the columns that reach the features (not the view PE).
  const double in_grad = in - 2.0 * 3 * cfg.viewdir_pe_freqs;
  const double bwd_flops =
      2.0 * n * (2.0 * H * 3 + 2.0 * H * H + (double(in) + in_grad) * H + 2.0 * double(F) * P);

  std::mt19937 rng(1);
  std::normal_distribution<float> normal(0.0f, 0.3f);
  std::vector<float> products(static_cast<size_t>(n) * P), viewdirs(3 * static_cast<size_t>(n));
  for (float& v : products) v = normal(rng);
  for (int i = 0; i < n; ++i) {
    float d[3] = {normal(rng), normal(rng), normal(rng) + 0.01f};
    const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int c = 0; c < 3; ++c) viewdirs[3 * i + c] = d[c] / len;
  }
  std::vector<float> rgb(3 * static_cast<size_t>(n)), dl_drgb(rgb.size()),
      dl_dproducts(products.size());
  for (float& v : dl_drgb) v = normal(rng);

  // The decoder's MLP (decoder/mlp.h: separate multiplies and adds, SPEC.md 7.6) on the same
  // weights and rows, each thread on its share of the rows. Its figure counts every term, also
  // those it skips (inputs that are zero after a ReLU): a dense-equivalent rate.
  dec::MlpConfig dcfg;
  dcfg.num_products = P;
  dcfg.feature_dim = F;
  dcfg.feature_pe_freqs = cfg.feature_pe_freqs;
  dcfg.viewdir_pe_freqs = cfg.viewdir_pe_freqs;
  dcfg.hidden = H;
  dec::AppearanceMlp decoder_mlp;
  if (!decoder_mlp.Init(dcfg).ok() ||
      !decoder_mlp.SetParams(head.params().data(), head.params().size()).ok()) {
    std::fprintf(stderr, "bench mlp: the decoder MLP refused the head's parameters\n");
    return 1;
  }

  nlohmann::json report;
  report["n"] = n;
  report["chunk_rows"] = chunk;
  report["statistic"] = g_use_best ? "min" : "median";
  report["eigen_simd"] = Eigen::SimdInstructionSetsInUse();
  report["small_gemm_isa"] = trainer::SmallGemmIsa();
  report["fma_peak_isa"] = FmaPeakIsa();
  std::printf("bench mlp: n=%d, chunk=%d rows, SmallGemm: %s, FMA peak loop: %s, Eigen SIMD: %s\n",
              n, chunk, trainer::SmallGemmIsa(), FmaPeakIsa(), Eigen::SimdInstructionSetsInUse());
  for (int threads : thread_counts) {
    const double peak = MeasureFmaPeakGflops(threads);
    // Eigen's GEMM (its own threading) on the shape of the first MLP layer, for comparison.
    Eigen::setNbThreads(threads);
    omp_set_num_threads(threads);
    const int gm = 4096, gk = 150, gn = 128;
    RowMat a = RowMat::Random(gm, gk), b = RowMat::Random(gk, gn), c(gm, gn);
    const double gemm_s = MedianSeconds(std::max(reps, 20), [&] { c.noalias() = a * b; });
    const double gemm_gflops = 2.0 * gm * gk * gn / gemm_s * 1e-9;

    const double fwd_s =
        MedianSeconds(reps, [&] { head.Forward(n, products.data(), viewdirs.data(), rgb.data()); });
    head.Forward(n, products.data(), viewdirs.data(), rgb.data());
    const double bwd_s =
        MedianSeconds(reps, [&] { head.Backward(n, dl_drgb.data(), dl_dproducts.data()); });
    const double inf_s =
        MedianSeconds(reps, [&] { head.Infer(n, products.data(), viewdirs.data(), rgb.data()); });
    std::vector<std::vector<float>> scratch(threads,
                                            std::vector<float>(decoder_mlp.ScratchFloats()));
    const double dec_s = MedianSeconds(reps, [&] {
#pragma omp parallel num_threads(threads)
      {
        const int t = omp_get_thread_num(), nt = omp_get_num_threads();
        const int r0 = int(long(n) * t / nt), r1 = int(long(n) * (t + 1) / nt);
        decoder_mlp.Infer(r1 - r0, products.data() + size_t(r0) * P, P,
                          viewdirs.data() + size_t(r0) * 3, rgb.data() + size_t(r0) * 3,
                          scratch[t].data());
      }
    });
    double adam_s = 0.0;
    if (adam_size > 0) {
      std::vector<float> p(static_cast<size_t>(adam_size), 0.5f), g(p.size(), 0.25f);
      trainer::Adam adam(p.size(), trainer::AdamConfig{});
      adam_s = MedianSeconds(reps, [&] { adam.Step(p.data(), g.data(), p.size(), 1e-3f); });
    }
    std::printf("threads=%d  FMA peak %.1f GFLOP/s; Eigen GEMM %dx%dx%d %.1f GFLOP/s (%.0f%%)\n",
                threads, peak, gm, gk, gn, gemm_gflops, 100.0 * gemm_gflops / peak);
    std::printf("  forward  %8.2f ms  %6.1f GFLOP/s (%.0f%% of peak)\n", fwd_s * 1e3,
                fwd_flops / fwd_s * 1e-9, 100.0 * fwd_flops / fwd_s * 1e-9 / peak);
    std::printf("  backward %8.2f ms  %6.1f GFLOP/s (%.0f%% of peak)\n", bwd_s * 1e3,
                bwd_flops / bwd_s * 1e-9, 100.0 * bwd_flops / bwd_s * 1e-9 / peak);
    std::printf("  infer    %8.2f ms  %6.1f GFLOP/s (%.0f%% of peak)\n", inf_s * 1e3,
                fwd_flops / inf_s * 1e-9, 100.0 * fwd_flops / inf_s * 1e-9 / peak);
    std::printf(
        "  decoder  %8.2f ms  %6.1f GFLOP/s (%.0f%% of the non-FMA peak %.1f; %s kernel, "
        "separate multiplies and adds)\n",
        dec_s * 1e3, fwd_flops / dec_s * 1e-9, 100.0 * fwd_flops / dec_s * 1e-9 / (peak / 2),
        peak / 2, dec::GemmKernelName(decoder_mlp.gemm_kernel()));
    if (adam_size > 0) {
      std::printf("  adam     %8.2f ms for %ld floats (%.1f GB/s of 7 streams)\n", adam_s * 1e3,
                  adam_size, 7.0 * 4 * adam_size / adam_s * 1e-9);
    }
    nlohmann::json& r = report["threads"][std::to_string(threads)];
    r["fma_peak_gflops"] = peak;
    r["eigen_gemm_gflops"] = gemm_gflops;
    r["forward_ms"] = fwd_s * 1e3;
    r["forward_gflops"] = fwd_flops / fwd_s * 1e-9;
    r["backward_ms"] = bwd_s * 1e3;
    r["backward_gflops"] = bwd_flops / bwd_s * 1e-9;
    r["infer_ms"] = inf_s * 1e3;
    r["infer_gflops"] = fwd_flops / inf_s * 1e-9;
    r["decoder_infer_ms"] = dec_s * 1e3;
    r["decoder_infer_gflops"] = fwd_flops / dec_s * 1e-9;
    if (adam_size > 0) r["adam_ms"] = adam_s * 1e3;
  }
  omp_set_num_threads(saved_threads);
  Eigen::setNbThreads(saved_eigen_threads);
  if (!json_path.empty()) {
    try {
      trainer::WriteFileAtomically(json_path, report.dump(2) + "\n");
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench mlp: %s\n", e.what());
      return 1;
    }
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
