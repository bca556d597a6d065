// `ecrf render SCENE.ecrf (--views transforms_SPLIT.json | --orbit N) -o OUT_DIR`: PNG renders of
// a decoded stream, and `ecrf eval SCENE.ecrf --data DIR`: PSNR / SSIM against a test split.
// Both share the renderer's flags; eval names its view selection as `ecrf train` does
// (--test-stride, --max-test-views, --eval-downscale), and angles are degrees as in the viewer.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "decoder/camera.h"
#include "tools/cli.h"
#include "tools/cli_args.h"
#include "tools/commands.h"
#include "tools/decoded_scene.h"
#include "trainer/data/camera.h"
#include "trainer/data/file_io.h"
#include "trainer/train/checkpoint.h"

namespace ecrf {
namespace tools {
namespace {

struct CommonArgs {
  std::string scene;
  int threads = 0;  // 0: all cores
  bool int16 = false;
  int max_memory_mb = int(dec::kDefaultDecodeMemoryBudget >> 20);
  uint64_t decode_budget = dec::kDefaultDecodeWorkPerByte;
  dec::RenderOptions render;
};

// The flags both commands share: the stream, threads, grid storage, the renderer's speed knobs
// (SPEC.md 7.8) and the budgets against hostile files.
void AddCommonFlags(CLI::App* app, CommonArgs* c) {
  app->add_option("SCENE", c->scene, "the .ecrf stream")->type_name("FILE")->required();
  CLI::Option* threads = AddThreadsFlag(app, &c->threads);
  threads->description(threads->get_description() + "; the renderer uses at most " +
                       std::to_string(dec::kMaxRenderThreads));
  app->add_flag("--int16", c->int16, "keep the grids in 16-bit fixed point (half the memory)");
  const std::string knobs =
      "Speed knobs (SPEC.md 7.8; the defaults give the reference image up to early termination)";
  app->add_flag_callback(
         "--no-skip", [c] { c->render.skip_empty_space = false; },
         "do not skip empty space (same image, slower)")
      ->group(knobs);
  app->add_option("--early-stop", c->render.early_stop_transmittance,
                  "stop a ray when its transmittance is below T (0 = off)")
      ->type_name("T")
      ->check(CLI::Range(0.0f, 1.0f))
      ->capture_default_str()
      ->group(knobs);
  app->add_option("--samples", c->render.max_samples, "at most N samples per ray (0 = the scene's)")
      ->type_name("N")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str()
      ->group(knobs);
  app->add_option("--step-scale", c->render.step_scale, "S x the sample spacing, 1/S the samples")
      ->type_name("S")
      ->check(CLI::Range(dec::kMinStepScale, dec::kMaxStepScale))
      ->capture_default_str()
      ->group(knobs);
  app->add_option("--weight-threshold", c->render.weight_threshold,
                  "run the MLP only for samples of weight > W")
      ->type_name("W")
      ->check(CLI::Range(0.0f, 1.0f))
      ->default_str("the scene's")
      ->group(knobs);
  const std::string budgets = "Budgets against hostile files";
  app->add_option("--max-memory-mb", c->max_memory_mb,
                  "refuse scenes whose decoded grids, mask and MLP need more (megabytes)")
      ->type_name("N")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str()
      ->group(budgets);
  app->add_option("--decode-budget", c->decode_budget,
                  "refuse streams whose decoding costs more than 2^24 + N symbols per byte of "
                  "the file (0 = no limit)")
      ->type_name("N")
      ->capture_default_str()
      ->group(budgets);
  app->add_option("--sample-budget", c->render.sample_budget,
                  "refuse scenes whose rays take more samples (0 = no limit)")
      ->type_name("N")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str()
      ->group(budgets);
  app->add_option("--work-budget", c->render.work_budget,
                  "refuse views that cost more multiply-adds per pixel on average, and scenes "
                  "one sample of which costs more (0 = no limit)")
      ->type_name("N")
      ->capture_default_str()
      ->group(budgets);
}

// The renderer's thread count for --threads (0: every core, up to the renderer's limit), so that
// the figures printed name the count that ran.
int RenderThreads(const CommonArgs& c) {
  return std::min(c.threads > 0 ? c.threads : AllCores(), dec::kMaxRenderThreads);
}

dec::RenderOptions RenderOptionsFor(const CommonArgs& c) {
  dec::RenderOptions o = c.render;
  o.num_threads = RenderThreads(c);
  return o;
}

LoadedScene LoadScene(const CommonArgs& c) {
  return LoadSceneFile(c.scene, c.int16 ? dec::GridStorage::kInt16 : dec::GridStorage::kFloat32,
                       uint64_t(c.max_memory_mb) << 20, c.decode_budget);
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

trainer::Camera OrbitView(int width, int height, double azimuth_deg, double elevation_deg,
                          double radius) {
  const dec::Camera d =
      dec::OrbitCameraDegrees(width, height, azimuth_deg, elevation_deg, float(radius));
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
  int orbit = 0, width = 400, height = 400, max_views = 0;
  double radius = 4.0, elevation = 30.0;
  auto app =
      MakeCommand("render",
                  "PNG renders of a decoded stream: the cameras of a dataset split (--views) or "
                  "an orbit around the scene (--orbit), one PNG per view");
  CLI::Option* views_flag =
      app->add_option("--views", views,
                      "render the cameras of this split file (DIR/transforms_SPLIT.json)")
          ->type_name("FILE");
  CLI::Option* orbit_flag =
      app->add_option("--orbit", orbit,
                      "render N views on a circle around the scene, 360/N degrees apart")
          ->type_name("N")
          ->check(CLI::Range(1, 1000000));
  views_flag->excludes(orbit_flag);
  app->add_option("-o,--out", out, "the directory for the PNGs (created)")
      ->type_name("DIR")
      ->required();
  app->add_option("--max-views", max_views, "render at most N views (0 = all)")
      ->type_name("N")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  const std::string orbit_group = "Orbit (--orbit; the camera looks at the origin, +z up)";
  app->add_option("-W", width, "image width in pixels")
      ->type_name("N")
      ->check(CLI::Range(1, 65536))
      ->capture_default_str()
      ->group(orbit_group);
  app->add_option("-H", height, "image height in pixels")
      ->type_name("N")
      ->check(CLI::Range(1, 65536))
      ->capture_default_str()
      ->group(orbit_group);
  app->add_option("--radius", radius, "distance of the camera from the origin (scene units)")
      ->type_name("R")
      ->check(CLI::PositiveNumber)
      ->capture_default_str()
      ->group(orbit_group);
  app->add_option("--elevation", elevation, "angle of the camera above the xy plane, in degrees")
      ->type_name("DEG")
      ->check(CLI::Range(-90.0, 90.0))
      ->capture_default_str()
      ->group(orbit_group);
  AddCommonFlags(app.get(), &c);
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  if (views.empty() && orbit == 0) return UsageError(*app, "needs --views FILE or --orbit N");
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
      cameras.emplace_back(name, OrbitView(width, height, 360.0 * k / orbit, elevation, radius));
    }
  }
  if (max_views > 0 && cameras.size() > size_t(max_views)) cameras.resize(size_t(max_views));
  // The decoder's image limit, applied before anything is decoded or allocated.
  for (const auto& [name, camera] : cameras) {
    const int64_t pixels = int64_t(camera.width) * camera.height;
    if (pixels > dec::kMaxImagePixels) {
      return UsageError(*app, "view " + name + " is " + std::to_string(camera.width) + "x" +
                                  std::to_string(camera.height) + " = " + std::to_string(pixels) +
                                  " pixels; the decoder renders at most " +
                                  std::to_string(dec::kMaxImagePixels) +
                                  " pixels per image (lower -W / -H)");
    }
  }
  const LoadedScene s = LoadScene(c);
  MakeDirectory(out);
  double seconds = 0.0, max_work = 0.0;
  dec::RenderStats stats;
  for (const auto& [name, camera] : cameras) {
    const auto start = std::chrono::steady_clock::now();
    dec::RenderStats view;
    const trainer::Image img = RenderDecoded(*s.field, camera, RenderOptionsFor(c), &view);
    seconds += Seconds(start);
    stats.Add(view);
    max_work = std::max(max_work, static_cast<double>(view.work) /
                                      (static_cast<double>(camera.width) * camera.height));
    trainer::SavePng(out + "/" + name + ".png", img);
  }
  std::printf(
      "rendered %zu views into %s: %.1f ms/view (%d thread%s), decode %.1f ms, "
      "%.2f M samples/view, %.2f M MLP samples/view\n",
      cameras.size(), out.c_str(), 1e3 * seconds / std::max<size_t>(1, cameras.size()),
      RenderThreads(c), RenderThreads(c) == 1 ? "" : "s", 1e3 * s.decode_seconds,
      stats.samples / 1e6 / std::max<size_t>(1, cameras.size()),
      stats.color_samples / 1e6 / std::max<size_t>(1, cameras.size()));
  std::printf("work: %.0f multiply-adds per pixel on the costliest view (work budget %llu)\n",
              max_work, static_cast<unsigned long long>(c.render.work_budget));
  return 0;
}

int RunEval(int argc, char** argv) {
  CommonArgs c;
  std::string data, split = "test", json_path;
  int test_stride = 1, max_test_views = 0, eval_downscale = 1, image_scale = 1;
  std::string procedural;  // --scene NAME
  uint32_t seed = trainer::TrainOptions().seed;
  auto app = MakeCommand("eval",
                         "PSNR and SSIM of a decoded stream against the views of a test split, "
                         "with the render time per view");
  CLI::Option* data_flag =
      app->add_option("--data", data, "the dataset directory (as given to ecrf train)")
          ->type_name("DIR");
  CLI::Option* scene_flag =
      app->add_option("--scene", procedural,
                      "a procedural scene as `ecrf train --scene NAME` makes it")
          ->type_name("NAME")
          ->check(CLI::IsMember({"builtin", "capture", "forward"}));
  data_flag->excludes(scene_flag);
  app->add_option("--split", split, "the split to score")->type_name("NAME")->capture_default_str();
  app->add_option("--seed", seed, "the procedural scene's seed (as given to train)")
      ->type_name("N")
      ->capture_default_str();
  app->add_option("--test-stride", test_stride, "score every K-th view")
      ->type_name("K")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  app->add_option("--max-test-views", max_test_views, "score at most N views (0 = all)")
      ->type_name("N")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app->add_option("--eval-downscale", eval_downscale,
                  "score at 1/N of the image size (area filter; also for --scene), as train's "
                  "--eval-downscale")
      ->type_name("N")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app->add_option("--image-scale", image_scale,
                  "render at 1/K of the size, score the bilinear upsampling to full size (what a "
                  "viewer shows "
                  "while it refines)")
      ->type_name("K")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app->add_option("--json", json_path, "write the figures as JSON")->type_name("FILE");
  AddCommonFlags(app.get(), &c);
  AddRenamedFlag(app.get(), "--stride", "--test-stride");
  AddRenamedFlag(app.get(), "--downscale", "--eval-downscale");
  AddRenamedFlag(app.get(), "--max-views", "--max-test-views");
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  if (data.empty() && procedural.empty())
    return UsageError(*app, "needs --data DIR or --scene NAME");
  const LoadedScene s = LoadScene(c);
  const trainer::Dataset test =
      procedural.empty()
          ? trainer::LoadDataset(data, split, eval_downscale)
          : trainer::DownscaleViews(ProceduralDataset(procedural, split, seed), eval_downscale);
  const trainer::EvalResult r = EvaluateDecoded(*s.field, test, test_stride, max_test_views,
                                                RenderOptionsFor(c), false, image_scale);
  std::printf(
      "%s: %zu bytes, PSNR %.2f dB, SSIM %.4f over %d %s views; decode %.1f ms, render %.1f "
      "ms/view "
      "(%d thread%s, %s grids; %.1f samples, %.1f MLP samples per ray)\n",
      c.scene.c_str(), s.bytes.size(), r.psnr, r.ssim, r.views, split.c_str(),
      1e3 * s.decode_seconds, 1e3 * r.seconds_per_view, RenderThreads(c),
      RenderThreads(c) == 1 ? "" : "s", c.int16 ? "int16" : "float32", r.samples_per_ray,
      r.color_samples_per_ray);
  if (!json_path.empty()) {
    nlohmann::json j = {{"scene", c.scene},
                        {"bytes", s.bytes.size()},
                        {"psnr", r.psnr},
                        {"ssim", r.ssim},
                        {"views", r.views},
                        {"decode_seconds", s.decode_seconds},
                        {"render_seconds_per_view", r.seconds_per_view},
                        {"threads", RenderThreads(c)},
                        {"grid_storage", c.int16 ? "int16" : "float32"},
                        {"image_scale", image_scale},
                        {"downscale", eval_downscale},
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
