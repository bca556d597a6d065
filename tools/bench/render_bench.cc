#include "tools/bench/render_bench.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "decoder/camera.h"
#include "decoder/field_sampler.h"
#include "tools/bench/bench_json.h"
#include "tools/bench/benches.h"
#include "trainer/data/seconds_since.h"

namespace ecrf {
namespace tools {

using namespace dec;  // NOLINT(google-build-using-namespace): the decoder's types throughout

namespace {

struct Rng {
  uint64_t state;
  uint64_t Next() {  // SplitMix64
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double Uniform() { return static_cast<double>(Next() >> 11) * (1.0 / 9007199254740992.0); }
  float Normal() {
    const double u1 = Uniform() + 1e-300, u2 = Uniform();
    return static_cast<float>(std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2));
  }
};

void FillNormal(float* p, size_t n, float scale, Rng* rng) {
  for (size_t i = 0; i < n; ++i) p[i] = scale * rng->Normal();
}

}  // namespace

Status MakeBlobScene(int res, GridStorage storage, bool with_mask, uint32_t seed,
                     SceneField* scene) {
  ECRF_CHECK_OR_RETURN(scene != nullptr && res >= 2 && res <= kMaxGridRes, kErrInvalidArgument,
                       "MakeBlobScene: bad arguments");
  Rng rng{0x1234567ull + seed};
  SceneField& s = *scene;
  for (int a = 0; a < 3; ++a) {
    s.aabb_min[a] = -1.5f;
    s.aabb_max[a] = 1.5f;
    s.res[a] = res;
  }
  s.step_size = 0.f;
  s.n_samples = 0;
  s.has_mask = false;
  const int r3[3] = {res, res, res};
  const int dr[3] = {16, 16, 16}, ar[3] = {48, 48, 48};
  VmGrid density, appearance;
  ECRF_RETURN_IF_ERROR(density.Allocate(r3, dr, GridStorage::kFloat32));
  ECRF_RETURN_IF_ERROR(appearance.Allocate(r3, ar, GridStorage::kFloat32));
  // Separable smooth box (half-width 0.35, edge width 0.01 in normalized coordinates): a solid
  // object whose surface spans a few samples, like a trained scene, rather than a soft fog that
  // would send tens of samples per ray through the MLP.
  const float center[3] = {0.15f, -0.1f, 0.05f};  // normalized coordinates
  const float half = 0.35f, edge = 0.01f, amp = 8.f;
  auto gauss = [&](int axis, int i) {
    const float c = static_cast<float>(i) / static_cast<float>(res - 1) * 2.f - 1.f;
    const float z = (half - std::fabs(c - center[axis])) / edge;
    return 1.f / (1.f + std::exp(-z));
  };
  for (int m = 0; m < 3; ++m) {
    FillNormal(density.plane_f32[m].data(), density.plane_count(m), 0.05f, &rng);
    FillNormal(density.line_f32[m].data(), density.line_count(m), 0.05f, &rng);
    FillNormal(appearance.plane_f32[m].data(), appearance.plane_count(m), 0.1f, &rng);
    FillNormal(appearance.line_f32[m].data(), appearance.line_count(m), 0.1f, &rng);
    const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
    for (int y = 0; y < res; ++y) {
      for (int x = 0; x < res; ++x) {
        density.plane_f32[m][density.plane_index(m, y, x, 0)] = amp * gauss(u, x) * gauss(v, y);
      }
    }
    for (int i = 0; i < res; ++i) density.line_f32[m][density.line_index(m, i, 0)] = gauss(w, i);
  }
  if (storage == GridStorage::kInt16) {
    ECRF_RETURN_IF_ERROR(QuantizeGridInt16(density, &s.density));
    ECRF_RETURN_IF_ERROR(QuantizeGridInt16(appearance, &s.appearance));
  } else {
    s.density = static_cast<VmGrid&&>(density);
    s.appearance = static_cast<VmGrid&&>(appearance);
  }
  MlpConfig mc;
  mc.num_products = s.appearance.total_rank();
  ECRF_RETURN_IF_ERROR(s.mlp.Init(mc));
  HeapArray<float> params;
  ECRF_RETURN_IF_ERROR(params.Allocate(s.mlp.num_params()));
  {
    const int P = mc.num_products, F = mc.feature_dim, H = mc.hidden, in = mc.input_dim();
    float* p = params.data();
    auto uni = [&](int fan_in, size_t count) {
      const double b = 1.0 / std::sqrt(static_cast<double>(fan_in));
      for (size_t k = 0; k < count; ++k) *p++ = static_cast<float>((rng.Uniform() * 2.0 - 1.0) * b);
    };
    uni(P, static_cast<size_t>(F) * P);
    uni(in, static_cast<size_t>(H) * in);
    uni(in, H);
    uni(H, static_cast<size_t>(H) * H);
    uni(H, H);
    uni(H, 3 * static_cast<size_t>(H));
    for (int k = 0; k < 3; ++k) *p++ = 0.f;
  }
  ECRF_RETURN_IF_ERROR(s.mlp.SetParams(params.data(), params.size()));
  if (with_mask) {
    ECRF_RETURN_IF_ERROR(s.mask.Init(s.aabb_min, s.aabb_max, r3));
    const float step = s.StepSize();
    HeapArray<uint8_t> raw;
    ECRF_RETURN_IF_ERROR(raw.Allocate(static_cast<size_t>(res) * res * res));
    for (int z = 0; z < res; ++z) {
      for (int y = 0; y < res; ++y) {
        for (int x = 0; x < res; ++x) {
          const int ii[3] = {x, y, z};
          float cn[3];
          for (int a = 0; a < 3; ++a)
            cn[a] = static_cast<float>(ii[a]) / static_cast<float>(res - 1) * 2.f - 1.f;
          GridPoint gp;
          LocateGridPoint(cn, s.res, &gp);
          const float sigma = ActivateDensity(s.density_activation,
                                              DensityFeature(s.density, gp) + s.density_shift);
          const float alpha = 1.f - std::exp(-sigma * step);
          raw[(static_cast<size_t>(z) * res + y) * res + x] = alpha >= 1e-4f ? 1 : 0;
        }
      }
    }
    for (int z = 0; z < res; ++z) {
      for (int y = 0; y < res; ++y) {
        for (int x = 0; x < res; ++x) {
          bool on = false;
          for (int dz = -1; dz <= 1 && !on; ++dz)
            for (int dy = -1; dy <= 1 && !on; ++dy)
              for (int dx = -1; dx <= 1 && !on; ++dx) {
                const int X = x + dx, Y = y + dy, Z = z + dz;
                if (X < 0 || Y < 0 || Z < 0 || X >= res || Y >= res || Z >= res) continue;
                on = raw[(static_cast<size_t>(Z) * res + Y) * res + X] != 0;
              }
          if (on) s.mask.Set(x, y, z, true);
        }
      }
    }
    ECRF_RETURN_IF_ERROR(s.mask.BuildAcceleration());
    s.has_mask = true;
  }
  return s.Validate();
}

Status BenchmarkRender(const SceneField& scene, int width, int height, int threads, int views,
                       const RenderOptions& base_options, RenderBenchResult* result) {
  ECRF_CHECK_OR_RETURN(result != nullptr && views >= 1 && width > 0 && height > 0,
                       kErrInvalidArgument, "BenchmarkRender: bad arguments");
  RenderOptions opt = base_options;
  opt.num_threads = threads;
  RayMarcher marcher;
  ECRF_RETURN_IF_ERROR(marcher.Init(&scene, opt));
  HeapArray<uint8_t> image;
  size_t bytes = 0;
  ECRF_CHECK_OR_RETURN(
      CheckedMul(static_cast<size_t>(width) * 4, static_cast<size_t>(height), &bytes), kErrLimit,
      "BenchmarkRender: image too large");
  ECRF_RETURN_IF_ERROR(image.Allocate(bytes));
  RenderStats stats;
  ECRF_RETURN_IF_ERROR(marcher.RenderImage(OrbitCamera(width, height, 0.3f, 0.5f, 4.f),
                                           image.data(), nullptr, &stats));  // warm-up
  RenderStats total;
  const auto start = std::chrono::steady_clock::now();
  for (int v = 0; v < views; ++v) {
    const float az = 0.3f + 6.283185f * static_cast<float>(v) / static_cast<float>(views);
    ECRF_RETURN_IF_ERROR(marcher.RenderImage(OrbitCamera(width, height, az, 0.5f, 4.f),
                                             image.data(), nullptr, &stats));
    total.Add(stats);
  }
  const double sec = trainer::SecondsSince(start);
  result->threads = threads;
  result->views = views;
  result->ms_per_view = sec * 1e3 / views;
  result->msamples_per_s = sec > 0 ? static_cast<double>(total.samples) / sec * 1e-6 : 0.0;
  result->mcolor_samples_per_s =
      sec > 0 ? static_cast<double>(total.color_samples) / sec * 1e-6 : 0.0;
  result->samples_per_view = total.samples / static_cast<uint64_t>(views);
  result->color_samples_per_view = total.color_samples / static_cast<uint64_t>(views);
  uint64_t hash = 14695981039346656037ull;
  for (size_t i = 0; i < bytes; ++i) hash = (hash ^ image.data()[i]) * 1099511628211ull;
  result->image_hash = hash;
  return Status::Ok();
}

int RunRenderBench(int argc, char** argv) {
  int res = 128, width = 400, height = 400, views = 2;
  bool int16 = false, no_skip = false;
  std::string threads = "1,0", json_path;
  std::vector<std::string> kernels = {"best"};
  auto app = MakeCommand(
      "bench render",
      "the renderer's speed on a synthetic res^3 blob scene (ranks 16/48, hidden 128, alpha "
      "mask): milliseconds per view and samples per second, per thread count");
  app->add_option("--res", res, "grid resolution per axis")
      ->type_name("N")
      ->check(CLI::Range(8, 512))
      ->capture_default_str();
  app->add_option("--width", width, "image width")
      ->type_name("PIXELS")
      ->check(CLI::Range(1, 8192))
      ->capture_default_str();
  app->add_option("--height", height, "image height")
      ->type_name("PIXELS")
      ->check(CLI::Range(1, 8192))
      ->capture_default_str();
  app->add_option("--views", views, "timed orbit views (after one warm-up view)")
      ->type_name("N")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app->add_flag("--int16", int16, "int16 grids (as a decoded file holds them) instead of float32");
  app->add_flag("--no-skip", no_skip, "march every sample (no empty-space skipping)");
  AddThreadListFlag(app.get(), &threads);
  app->add_option("--kernels", kernels,
                  "MLP matrix kernels to time, one after the other: best (the one the decoder "
                  "picks), all (every one this CPU runs: they give identical pixels), or a list "
                  "of portable, avx2, avx512")
      ->type_name("LIST")
      ->delimiter(',')
      ->capture_default_str();
  app->add_option("--json", json_path, "also write the figures as JSON")->type_name("FILE");
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  // The kernels to time; with one (the default) the JSON keys are those of earlier versions.
  std::vector<GemmKernel> kernel_list;
  for (const std::string& name : kernels) {
    bool known = false;
    for (const GemmKernel k : {GemmKernel::kPortable, GemmKernel::kAvx2, GemmKernel::kAvx512}) {
      const bool wanted = name == GemmKernelName(k) || (name == "all" && GemmKernelAvailable(k)) ||
                          (name == "best" && k == BestGemmKernel());
      known |= wanted || name == "all" || name == "best";
      if (!wanted) continue;
      if (!GemmKernelAvailable(k)) {
        std::fprintf(stderr, "bench render: the %s kernel does not run on this CPU or build\n",
                     GemmKernelName(k));
        return 2;
      }
      kernel_list.push_back(k);
    }
    if (!known) {
      std::fprintf(stderr,
                   "bench render: --kernels: unknown kernel '%s' (best, all, portable, avx2, "
                   "avx512)\n",
                   name.c_str());
      return 2;
    }
  }

  SceneField scene;
  const auto t0 = std::chrono::steady_clock::now();
  if (const Status st =
          MakeBlobScene(res, int16 ? GridStorage::kInt16 : GridStorage::kFloat32, true, 1, &scene);
      !st.ok()) {
    std::fprintf(stderr, "bench render: %s\n", st.message());
    return 1;
  }
  std::printf(
      "bench render: %d^3 blob scene (%s grids, built in %.0f ms), %dx%d, %d views, skipping %s\n",
      res, int16 ? "int16" : "float32", trainer::SecondsSince(t0) * 1e3, width, height, views,
      no_skip ? "off" : "on");
  BenchReport report;
  RenderOptions options;
  options.skip_empty_space = !no_skip;
  uint64_t first_hash = 0;
  bool identical = true;
  for (size_t ki = 0; ki < kernel_list.size(); ++ki) {
    const GemmKernel kernel = kernel_list[ki];
    if (!scene.mlp.UseGemmKernel(kernel).ok()) return 1;  // checked available above
    std::printf("MLP kernel: %s\n", GemmKernelName(kernel));
    const std::string prefix =
        kernel_list.size() > 1 ? std::string(GemmKernelName(kernel)) + "." : std::string();
    for (int t : ThreadCounts(threads)) {
      RenderBenchResult r;
      if (const Status st = BenchmarkRender(scene, width, height, t, views, options, &r);
          !st.ok()) {
        std::fprintf(stderr, "bench render: %s\n", st.message());
        return 1;
      }
      if (ki == 0 && first_hash == 0) first_hash = r.image_hash;
      identical &= r.image_hash == first_hash;
      const std::string key = prefix + "threads_" + std::to_string(t) + ".";
      report.Add(key + "ms_per_view", r.ms_per_view, "ms");
      report.Add(key + "msamples_per_s", r.msamples_per_s, "M samples/s");
      report.Add(key + "mcolor_samples_per_s", r.mcolor_samples_per_s, "M MLP samples/s");
      report.Add(key + "samples_per_view", static_cast<double>(r.samples_per_view), "samples");
      report.Add(key + "color_samples_per_view", static_cast<double>(r.color_samples_per_view),
                 "MLP samples");
    }
  }
  // Kernels and thread counts never change a pixel (decoder/mlp_gemm.h, SPEC.md 7.8).
  std::printf("pixels of every kernel and thread count: %s\n",
              identical ? "identical" : "DIFFERENT");
  if (!identical) return 1;
  if (!json_path.empty() && !report.WriteJson(json_path)) {
    std::fprintf(stderr, "bench render: cannot write %s\n", json_path.c_str());
    return 1;
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
