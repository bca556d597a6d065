// `ecrf bench mlp`: throughput of the appearance MLP (AppearanceHead, on SmallGemm) and Adam
// against this CPU's measured single-precision FMA peak, with Eigen's GEMM on the shape of the
// first MLP layer for comparison.
//
//   ecrf bench mlp [--n 131072] [--threads 1,2] [--reps 5] [--chunk 256] [--adam 20000000]
//                  [--best] [--json out.json]
// Times are medians of --reps runs, or the fastest run with --best.
#include <omp.h>

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "tools/cpu_peak.h"
#include "trainer/adam.h"
#include "trainer/appearance_head.h"
#include "trainer/small_gemm.h"

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

std::vector<int> ParseList(const char* s) {
  std::vector<int> out;
  std::string str(s);
  size_t pos = 0;
  while (pos <= str.size()) {
    const size_t comma = std::min(str.find(',', pos), str.size());
    if (comma > pos) out.push_back(std::atoi(str.substr(pos, comma - pos).c_str()));
    pos = comma + 1;
  }
  return out;
}

}  // namespace

int RunMlpBench(int argc, char** argv) {
  int n = 131072, reps = 5, chunk = 256;
  long adam_size = 20000000;
  std::vector<int> thread_counts = {1, std::max(1, omp_get_max_threads())};
  std::string json_path;
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (!std::strcmp(argv[i], "--n") && has_value) {
      n = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--reps") && has_value) {
      reps = std::max(1, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--chunk") && has_value) {
      chunk = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--threads") && has_value) {
      thread_counts = ParseList(argv[++i]);
    } else if (!std::strcmp(argv[i], "--adam") && has_value) {
      adam_size = std::atol(argv[++i]);
    } else if (!std::strcmp(argv[i], "--best")) {
      g_use_best = true;
    } else if (!std::strcmp(argv[i], "--json") && has_value) {
      json_path = argv[++i];
    } else {
      std::fprintf(stderr,
                   "usage: ecrf bench mlp [--n N] [--threads 1,2] [--reps R] [--chunk ROWS] "
                   "[--adam FLOATS] [--best] [--json PATH]\n");
      return 2;
    }
  }
  thread_counts.erase(std::remove_if(thread_counts.begin(), thread_counts.end(),
                                     [](int t) { return t < 1; }),
                      thread_counts.end());
  if (n < 1 || thread_counts.empty()) {
    std::fprintf(stderr, "bench mlp: need --n >= 1 and at least one thread count\n");
    return 2;
  }
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

    const double fwd_s = MedianSeconds(reps, [&] {
      head.Forward(n, products.data(), viewdirs.data(), rgb.data());
    });
    head.Forward(n, products.data(), viewdirs.data(), rgb.data());
    const double bwd_s = MedianSeconds(reps, [&] {
      head.Backward(n, dl_drgb.data(), dl_dproducts.data());
    });
    const double inf_s = MedianSeconds(reps, [&] {
      head.Infer(n, products.data(), viewdirs.data(), rgb.data());
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
    if (adam_size > 0) r["adam_ms"] = adam_s * 1e3;
  }
  omp_set_num_threads(saved_threads);
  Eigen::setNbThreads(saved_eigen_threads);
  if (!json_path.empty()) {
    std::ofstream out(json_path);
    out << report.dump(2) << "\n";
    if (!out) {
      std::fprintf(stderr, "bench mlp: cannot write %s\n", json_path.c_str());
      return 1;
    }
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
