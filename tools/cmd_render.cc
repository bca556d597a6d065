// `ecrf render SCENE.ecrf (--views transforms_SPLIT.json | --orbit N) -o OUT_DIR`: PNG renders of
// a decoded stream, and `ecrf eval SCENE.ecrf --data DIR`: PSNR / SSIM against a test split.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "tools/cli_args.h"
#include "tools/commands.h"
#include "tools/decoded_scene.h"
#include "trainer/camera.h"
#include "trainer/checkpoint.h"

namespace ecrf {
namespace tools {
namespace {

const char kRenderUsage[] =
    "usage: ecrf render SCENE.ecrf (--views DIR/transforms_SPLIT.json | --orbit N) -o OUT_DIR\n"
    "  -W N, -H N          image size for --orbit (default 400x400)\n"
    "  --radius R          orbit radius (default 4)\n"
    "  --elevation DEG     orbit elevation (default 30)\n"
    "  --max-views N       render at most N views\n"
    "  --threads N         render threads (default 1; 0 = all cores)\n"
    "  --int16             keep the grids in 16-bit fixed point (half the memory)\n";

const char kEvalUsage[] =
    "usage: ecrf eval SCENE.ecrf (--data DIR | --scene builtin|capture|forward) [options]\n"
    "  --split NAME        split to score (default test)\n"
    "  --seed N            the procedural scene's seed (as given to train)\n"
    "  --downscale N       score at 1/N of the image size (area filter; also for --scene)\n"
    "  --image-scale K     render at 1/K of the size, score the bilinear upsampling to full size\n"
    "  --stride K          every K-th view\n"
    "  --max-views N       at most N views\n"
    "  --threads N         render threads (default 1; 0 = all cores)\n"
    "  --int16             16-bit fixed-point grids\n"
    "  --json FILE         write the figures as JSON\n";

// Speed knobs of the renderer (SPEC.md 7.8), shared by render and eval.
const char kRenderKnobUsage[] =
    "speed knobs (SPEC.md 7.8; defaults give the reference image up to early termination):\n"
    "  --no-skip           do not skip empty space (same image, slower)\n"
    "  --early-stop T      stop a ray when its transmittance is below T (default 1e-4; 0 = off)\n"
    "  --samples N         at most N samples per ray (default: the scene's)\n"
    "  --step-scale S      S x the sample spacing, 1/S the samples (default 1)\n"
    "  --weight-threshold W  run the MLP only for samples of weight > W (default: the scene's)\n"
    "budgets against hostile files:\n"
    "  --max-memory-mb N   refuse scenes whose decoded grids, mask and MLP need more (default 256)\n"
    "  --sample-budget N   refuse scenes whose rays take more samples (default 16384; 0 = no limit)\n";

void PrintUsage(FILE* out, const char* usage) {
  std::fputs(usage, out);
  std::fputs(kRenderKnobUsage, out);
}

struct CommonArgs {
  std::string scene;
  int threads = 1;
  bool int16 = false;
  int max_views = 0;
  uint64_t max_memory_bytes = dec::kDefaultDecodeMemoryBudget;
  dec::RenderOptions render;
};

// Consumes the flags both commands share; false if argv[i] is not one of them.
bool ParseCommon(int argc, char** argv, int* i, CommonArgs* c) {
  const std::string a = argv[*i];
  auto value = [&] { return FlagValue(argc, argv, i); };
  if (a == "--threads") {
    c->threads = ParseInt("--threads", value());
  } else if (a == "--int16") {
    c->int16 = true;
  } else if (a == "--max-views") {
    c->max_views = ParseInt("--max-views", value());
  } else if (a == "--no-skip") {
    c->render.skip_empty_space = false;
  } else if (a == "--early-stop") {
    c->render.early_stop_transmittance = ParseFloat("--early-stop", value());
  } else if (a == "--samples") {
    c->render.max_samples = ParseInt("--samples", value());
  } else if (a == "--step-scale") {
    c->render.step_scale = ParseFloat("--step-scale", value());
  } else if (a == "--weight-threshold") {
    c->render.weight_threshold = ParseFloat("--weight-threshold", value());
  } else if (a == "--max-memory-mb") {
    const int mb = ParseInt("--max-memory-mb", value());
    if (mb < 1) throw std::invalid_argument("--max-memory-mb must be at least 1");
    c->max_memory_bytes = uint64_t(mb) << 20;
  } else if (a == "--sample-budget") {
    c->render.sample_budget = ParseInt("--sample-budget", value());
    if (c->render.sample_budget < 0) throw std::invalid_argument("--sample-budget must be >= 0 (0: no limit)");
  } else if (a[0] != '-' && c->scene.empty()) {
    c->scene = a;
  } else {
    return false;
  }
  return true;
}

dec::RenderOptions RenderOptionsFor(const CommonArgs& c) {
  dec::RenderOptions o = c.render;
  o.num_threads = c.threads;
  return o;
}

// "DIR/transforms_test.json" -> DIR, "test".
void SplitViewsPath(const std::string& path, std::string* dir, std::string* split) {
  const size_t slash = path.find_last_of('/');
  *dir = slash == std::string::npos ? "." : path.substr(0, slash);
  const std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  const std::string prefix = "transforms_", suffix = ".json";
  if (base.size() <= prefix.size() + suffix.size() || base.compare(0, prefix.size(), prefix) ||
      base.compare(base.size() - suffix.size(), suffix.size(), suffix)) {
    throw std::invalid_argument("--views: '" + path + "' is not named transforms_SPLIT.json");
  }
  *split = base.substr(prefix.size(), base.size() - prefix.size() - suffix.size());
}

trainer::Camera OrbitView(int width, int height, double azimuth, double elevation, double radius) {
  const dec::Camera d = dec::OrbitCamera(width, height, float(azimuth), float(elevation), float(radius));
  trainer::Camera c;
  c.width = width;
  c.height = height;
  c.fx = d.fx;
  c.fy = d.fy;
  c.cx = d.cx;
  c.cy = d.cy;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 4; ++k) c.c2w[r][k] = d.c2w[r * 4 + k];
  }
  return c;
}

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int RunRender(int argc, char** argv) {
  CommonArgs c;
  std::string views, out;
  int orbit = 0, width = 400, height = 400;
  double radius = 4.0, elevation = 30.0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&] { return FlagValue(argc, argv, &i); };
    if (a == "--help" || a == "-h") {
      PrintUsage(stdout, kRenderUsage);
      return 0;
    } else if (a == "--views") {
      views = value();
    } else if (a == "--orbit") {
      orbit = ParseInt("--orbit", value());
    } else if (a == "-W") {
      width = ParseInt("-W", value());
    } else if (a == "-H") {
      height = ParseInt("-H", value());
    } else if (a == "--radius") {
      radius = ParseFloat("--radius", value());
    } else if (a == "--elevation") {
      elevation = ParseFloat("--elevation", value());
    } else if (a == "-o" || a == "--out") {
      out = value();
    } else if (!ParseCommon(argc, argv, &i, &c)) {
      std::fprintf(stderr, "ecrf render: unexpected argument '%s'\n", a.c_str());
      PrintUsage(stderr, kRenderUsage);
      return 2;
    }
  }
  if (c.scene.empty() || out.empty() || (views.empty() == (orbit == 0)) || width < 1 || height < 1) {
    std::fprintf(stderr, "ecrf render: needs SCENE.ecrf, -o OUT_DIR and one of --views / --orbit\n\n");
    PrintUsage(stderr, kRenderUsage);
    return 2;
  }
  std::vector<std::pair<std::string, trainer::Camera>> cameras;
  if (!views.empty()) {
    std::string dir, split;
    SplitViewsPath(views, &dir, &split);
    for (const trainer::ViewSource& v : trainer::ReadDatasetManifest(dir, split).views) {
      std::string name = v.name;
      for (char& ch : name) {
        if (ch == '/') ch = '_';
      }
      cameras.emplace_back(name, v.camera);
    }
  } else {
    for (int k = 0; k < orbit; ++k) {
      char name[32];
      std::snprintf(name, sizeof(name), "orbit_%03d", k);
      cameras.emplace_back(name, OrbitView(width, height, 2.0 * M_PI * k / orbit,
                                           elevation * M_PI / 180.0, radius));
    }
  }
  if (c.max_views > 0 && cameras.size() > size_t(c.max_views)) cameras.resize(size_t(c.max_views));
  const LoadedScene s = LoadSceneFile(c.scene, c.int16 ? dec::GridStorage::kInt16 : dec::GridStorage::kFloat32,
                                      c.max_memory_bytes);
  MakeDirectory(out);
  double seconds = 0.0;
  dec::RenderStats stats;
  for (const auto& [name, camera] : cameras) {
    const auto start = std::chrono::steady_clock::now();
    const trainer::Image img = RenderDecoded(*s.field, camera, RenderOptionsFor(c), &stats);
    seconds += Seconds(start);
    trainer::SavePng(out + "/" + name + ".png", img);
  }
  std::printf("rendered %zu views into %s: %.1f ms/view (%d thread%s), decode %.1f ms, "
              "%.2f M samples/view, %.2f M MLP samples/view\n",
              cameras.size(), out.c_str(), 1e3 * seconds / std::max<size_t>(1, cameras.size()), c.threads,
              c.threads == 1 ? "" : "s", 1e3 * s.decode_seconds,
              stats.samples / 1e6 / std::max<size_t>(1, cameras.size()),
              stats.color_samples / 1e6 / std::max<size_t>(1, cameras.size()));
  return 0;
}

int RunEval(int argc, char** argv) {
  CommonArgs c;
  std::string data, split = "test", json_path;
  int stride = 1, downscale = 1, image_scale = 1;
  std::string procedural;  // --scene NAME
  uint32_t seed = trainer::TrainOptions().seed;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&] { return FlagValue(argc, argv, &i); };
    if (a == "--help" || a == "-h") {
      PrintUsage(stdout, kEvalUsage);
      return 0;
    } else if (a == "--data") {
      data = value();
    } else if (a == "--scene") {
      procedural = value();
      trainer::TrainOptions check;
      trainer::SelectProceduralScene(procedural, &check);  // a bad name fails before the scene loads
    } else if (a == "--seed") {
      seed = uint32_t(ParseInt("--seed", value()));
    } else if (a == "--split") {
      split = value();
    } else if (a == "--stride") {
      stride = std::max(1, ParseInt("--stride", value()));
    } else if (a == "--downscale") {
      downscale = std::max(1, ParseInt("--downscale", value()));
    } else if (a == "--image-scale") {
      image_scale = std::max(1, ParseInt("--image-scale", value()));
    } else if (a == "--json") {
      json_path = value();
    } else if (!ParseCommon(argc, argv, &i, &c)) {
      std::fprintf(stderr, "ecrf eval: unexpected argument '%s'\n", a.c_str());
      PrintUsage(stderr, kEvalUsage);
      return 2;
    }
  }
  if (c.scene.empty() || data.empty() == procedural.empty()) {
    std::fprintf(stderr, "ecrf eval: needs SCENE.ecrf and one of --data DIR / --scene builtin|capture|forward\n\n");
    PrintUsage(stderr, kEvalUsage);
    return 2;
  }
  const LoadedScene s = LoadSceneFile(c.scene, c.int16 ? dec::GridStorage::kInt16 : dec::GridStorage::kFloat32,
                                      c.max_memory_bytes);
  const trainer::Dataset test = procedural.empty() ? trainer::LoadDataset(data, split, downscale)
                                                   : trainer::DownscaleViews(ProceduralDataset(procedural, split, seed), downscale);
  const trainer::EvalResult r = EvaluateDecoded(*s.field, test, stride, c.max_views, RenderOptionsFor(c), false, image_scale);
  std::printf("%s: %zu bytes, PSNR %.2f dB, SSIM %.4f over %d %s views; decode %.1f ms, render %.1f ms/view "
              "(%d thread%s, %s grids; %.1f samples, %.1f MLP samples per ray)\n",
              c.scene.c_str(), s.bytes.size(), r.psnr, r.ssim, r.views, split.c_str(), 1e3 * s.decode_seconds,
              1e3 * r.seconds_per_view, c.threads, c.threads == 1 ? "" : "s", c.int16 ? "int16" : "float32",
              r.samples_per_ray, r.color_samples_per_ray);
  if (!json_path.empty()) {
    nlohmann::json j = {{"scene", c.scene},          {"bytes", s.bytes.size()},
                        {"psnr", r.psnr},            {"ssim", r.ssim},
                        {"views", r.views},          {"decode_seconds", s.decode_seconds},
                        {"render_seconds_per_view", r.seconds_per_view},
                        {"threads", c.threads},      {"grid_storage", c.int16 ? "int16" : "float32"},
                        {"image_scale", image_scale},
                        {"downscale", downscale},
                        {"samples_per_ray", r.samples_per_ray},
                        {"mlp_samples_per_ray", r.color_samples_per_ray},
                        {"render_options",
                         {{"skip_empty_space", c.render.skip_empty_space},
                          {"early_stop_transmittance", c.render.early_stop_transmittance},
                          {"max_samples", c.render.max_samples},
                          {"step_scale", c.render.step_scale},
                          {"weight_threshold", c.render.weight_threshold}}}};
    const std::string text = j.dump(2) + "\n";
    trainer::WriteFileAtomically(json_path, text.data(), text.size());
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
