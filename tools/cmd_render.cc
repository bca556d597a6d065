// `ecrf render SCENE.ecrf (--views transforms_SPLIT.json | --orbit N | --spiral N | --path FILE)
// [-o OUT_DIR] [--video OUT.mp4]`: PNG renders of a decoded stream and videos of camera paths
// (tools/camera_path.h, tools/video_writer.h), and `ecrf eval SCENE.ecrf --data DIR`: PSNR / SSIM
// against a test split.
// Both share the renderer's flags; eval names its view selection as `ecrf train` does
// (--test-stride, --max-test-views, --eval-downscale), and angles are degrees as in the viewer.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "tools/camera_path.h"
#include "tools/camera_path_json.h"
#include "tools/cli.h"
#include "tools/cli_args.h"
#include "tools/commands.h"
#include "tools/decoded_scene.h"
#include "tools/run_program.h"
#include "tools/video_writer.h"
#include "trainer/data/camera.h"
#include "trainer/data/file_io.h"
#include "trainer/data/seconds_since.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/eval_progress.h"
#include "trainer/train/evaluate.h"

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

// Where render's cameras come from: exactly one of --views, --orbit, --spiral, --path.
struct CameraArgs {
  std::string views, path_file, save_path;
  int orbit = 0, spiral = 0, max_views = 0;
  OrbitShape shape;
  SpiralShape spiral_shape;
};

struct VideoArgs {
  std::string output;
  int fps = 30;
  std::string ffmpeg = "ffmpeg";
};

void AddCameraFlags(CLI::App* app, CameraArgs* a) {
  // One source at most, checked after parsing (CameraSourceProblem): CLI11's excludes() would
  // list the others in --help in an order that changes from run to run.
  app->add_option("--views", a->views,
                  "render the cameras of this split file (DIR/transforms_SPLIT.json), named "
                  "as its frames")
      ->type_name("FILE");
  app->add_option("--orbit", a->orbit,
                  "render N views on a circle around the scene, 360/N degrees apart "
                  "(orbit_000.png ...)")
      ->type_name("N")
      ->check(CLI::Range(1, 1000000));
  app->add_option("--spiral", a->spiral,
                  "render N views on a spiral: frame k of N, t = k/N, p = sin(2 pi C t) for "
                  "C = --spiral-cycles: azimuth 360 t, elevation = --elevation + "
                  "--spiral-elevation * p, radius = --radius * (1 + --spiral-radius * p) "
                  "(spiral_000.png ...)")
      ->type_name("N")
      ->check(CLI::Range(1, 1000000));
  app->add_option("--path", a->path_file,
                  "render the cameras of a JSON camera path (transforms.json convention: "
                  "camera_angle_x or fl_x/fl_y/cx/cy, w/h (default -W/-H), frames with "
                  "transform_matrix; path_000.png ...)")
      ->type_name("FILE");
  app->add_option("--save-path", a->save_path,
                  "write the cameras rendered as a --path JSON file (alone: write it, render "
                  "nothing)")
      ->type_name("FILE");
  app->add_option("--max-views", a->max_views, "render at most N views (0 = all)")
      ->type_name("N")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  const std::string orbit_group =
      "Orbit and spiral (--orbit, --spiral; the camera looks at the origin, +z up)";
  app->add_option("-W,--width", a->shape.width,
                  "image width in pixels (also --path files without 'w')")
      ->type_name("N")
      ->check(CLI::Range(1, 65536))
      ->capture_default_str()
      ->group(orbit_group);
  app->add_option("-H,--height", a->shape.height,
                  "image height in pixels (also --path files without 'h')")
      ->type_name("N")
      ->check(CLI::Range(1, 65536))
      ->capture_default_str()
      ->group(orbit_group);
  app->add_option("--radius", a->shape.radius,
                  "distance of the camera from the origin (scene units)")
      ->type_name("R")
      ->check(CLI::PositiveNumber)
      ->capture_default_str()
      ->group(orbit_group);
  app->add_option("--elevation", a->shape.elevation_deg,
                  "angle of the camera above the xy plane, in degrees")
      ->type_name("DEG")
      ->check(CLI::Range(-90.0, 90.0))
      ->capture_default_str()
      ->group(orbit_group);
  app->add_option("--spiral-elevation", a->spiral_shape.elevation_amplitude_deg,
                  "the spiral's elevation swing above and below --elevation, in degrees")
      ->type_name("DEG")
      ->check(CLI::Range(0.0, 90.0))
      ->capture_default_str()
      ->group(orbit_group);
  app->add_option("--spiral-radius", a->spiral_shape.radius_amplitude,
                  "the spiral's radius swing, a fraction of --radius")
      ->type_name("F")
      ->check(CLI::Range(0.0, 0.99))
      ->capture_default_str()
      ->group(orbit_group);
  app->add_option("--spiral-cycles", a->spiral_shape.cycles,
                  "the spiral's up-and-down swings per turn (whole: the path loops)")
      ->type_name("C")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str()
      ->group(orbit_group);
}

// "" when exactly one camera source is given, else what is wrong.
std::string CameraSourceProblem(const CameraArgs& a) {
  std::vector<std::string> given;
  if (!a.views.empty()) given.push_back("--views");
  if (a.orbit > 0) given.push_back("--orbit");
  if (a.spiral > 0) given.push_back("--spiral");
  if (!a.path_file.empty()) given.push_back("--path");
  if (given.empty()) return "needs --views FILE or --orbit N (or --spiral N, --path FILE)";
  if (given.size() == 1) return "";
  std::string list;
  for (size_t i = 0; i < given.size(); ++i)
    list += (i == 0 ? "" : i + 1 == given.size() ? " and " : ", ") + given[i];
  return "give one camera source, not " + list;
}

void AddVideoFlags(CLI::App* app, VideoArgs* v) {
  const std::string group = "Video (--video; needs --orbit, --spiral or --path)";
  app->add_option("--video", v->output,
                  "encode the frames as an H.264 MP4 with ffmpeg; the PNGs stay only with -o. "
                  "Without ffmpeg: the frames go to -o DIR (else NAME_frames/ beside the video) "
                  "and the ffmpeg command is printed")
      ->type_name("FILE.mp4")
      ->group(group);
  app->add_option("--fps", v->fps, "frames per second of the video")
      ->type_name("N")
      ->check(CLI::Range(1, 240))
      ->capture_default_str()
      ->group(group);
  app->add_option("--ffmpeg", v->ffmpeg, "the ffmpeg program (a name looked up on PATH, or a path)")
      ->type_name("PROGRAM")
      ->capture_default_str()
      ->group(group);
}

// The cameras the flags ask for; *prefix is the name pattern's prefix for paths ("orbit"), "" for
// --views (named as the dataset's frames).
std::vector<PathCamera> CamerasFor(const CameraArgs& a, std::string* prefix) {
  std::vector<PathCamera> cameras;
  prefix->clear();
  if (!a.views.empty()) {
    std::string dir, split;
    SplitViewsPath(a.views, &dir, &split);
    for (const trainer::ViewSource& v : trainer::ReadDatasetManifest(dir, split).views) {
      std::string name = v.name;
      for (char& ch : name) {
        if (ch == '/') ch = '_';
      }
      cameras.push_back({name, v.camera});
    }
  } else if (a.orbit > 0) {
    *prefix = "orbit";
    cameras = OrbitPath(a.orbit, a.shape);
  } else if (a.spiral > 0) {
    *prefix = "spiral";
    cameras = SpiralPath(a.spiral, a.shape, a.spiral_shape);
  } else {
    *prefix = "path";
    cameras = ReadCameraPath(a.path_file, a.shape.width, a.shape.height);
  }
  if (a.max_views > 0 && cameras.size() > size_t(a.max_views)) cameras.resize(size_t(a.max_views));
  return cameras;
}

// The decoder's image limit, applied before anything is decoded or allocated, and for a video
// one size of at least 2x2 (H.264 in yuv420p); "" when the sizes are fine.
std::string SizeProblem(const std::vector<PathCamera>& cameras, bool video) {
  const auto size = [](const trainer::Camera& c) {
    return std::to_string(c.width) + "x" + std::to_string(c.height);
  };
  for (const auto& [name, camera] : cameras) {
    const int64_t pixels = int64_t(camera.width) * camera.height;
    if (pixels > dec::kMaxImagePixels) {
      return "view " + name + " is " + size(camera) + " = " + std::to_string(pixels) +
             " pixels; the decoder renders at most " + std::to_string(dec::kMaxImagePixels) +
             " pixels per image (lower -W / -H)";
    }
    if (!video) continue;
    const trainer::Camera& first = cameras[0].camera;
    if (camera.width != first.width || camera.height != first.height) {
      return "--video: view " + name + " is " + size(camera) + " but " + cameras[0].name + " is " +
             size(first) + "; a video's frames share one size";
    }
    if (camera.width < 2 || camera.height < 2) {
      return "--video: view " + name + " is " + size(camera) +
             "; a video needs at least 2x2 pixels";
    }
  }
  return "";
}

// Removes a temporary frames directory and everything in it, unless told to keep it.
class FramesCleanup {
 public:
  FramesCleanup() = default;
  ~FramesCleanup() {
    std::error_code error;
    if (!dir_.empty()) std::filesystem::remove_all(dir_, error);
  }
  FramesCleanup(const FramesCleanup&) = delete;
  FramesCleanup& operator=(const FramesCleanup&) = delete;
  void Track(const std::string& dir) { dir_ = dir; }
  void Keep() { dir_.clear(); }

 private:
  std::string dir_;
};

}  // namespace

int RunRender(int argc, char** argv) {
  CommonArgs c;
  CameraArgs a;
  VideoArgs video;
  std::string out;
  auto app = MakeCommand(
      "render",
      "PNG renders of a decoded stream, and videos: the cameras of a dataset split (--views), an "
      "orbit (--orbit) or spiral (--spiral) around the scene, or a camera path file (--path); one "
      "PNG per view into -o DIR, and/or an MP4 (--video)");
  AddCameraFlags(app.get(), &a);
  app->add_option("-o,--out", out, "the directory for the PNGs (created)")->type_name("DIR");
  AddVideoFlags(app.get(), &video);
  AddCommonFlags(app.get(), &c);
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  if (const std::string problem = CameraSourceProblem(a); !problem.empty())
    return UsageError(*app, problem);
  if (out.empty() && video.output.empty() && a.save_path.empty()) {
    return UsageError(*app, "needs -o DIR for PNGs or --video FILE.mp4 (or --save-path FILE)");
  }
  if (!video.output.empty() && !a.views.empty()) {
    return UsageError(*app,
                      "--video needs a camera path (--orbit, --spiral or --path); for a split's "
                      "cameras give --path " +
                          a.views);
  }
  if (a.spiral > 0) {
    if (const std::string problem = SpiralProblem(a.shape, a.spiral_shape); !problem.empty())
      return UsageError(*app, problem);
  }
  std::string prefix;
  const std::vector<PathCamera> cameras = CamerasFor(a, &prefix);
  if (const std::string problem = SizeProblem(cameras, !video.output.empty()); !problem.empty())
    return UsageError(*app, problem);
  if (!a.save_path.empty()) {
    WriteCameraPath(a.save_path, cameras);
    std::printf("wrote %zu cameras to %s\n", cameras.size(), a.save_path.c_str());
    if (out.empty() && video.output.empty()) return 0;
  }
  // Every output is proved writable before the scene is decoded and the frames rendered.
  std::string frames_dir = out, ffmpeg;
  FramesCleanup cleanup;
  if (!video.output.empty()) {
    CheckVideoOutput(video.output);
    ffmpeg = FindExecutable(video.ffmpeg);
    if (frames_dir.empty() && !ffmpeg.empty()) {
      frames_dir = MakeFramesDirectory(video.output);
      cleanup.Track(frames_dir);
    } else if (frames_dir.empty()) {
      frames_dir = video.output.substr(0, video.output.size() - 4) + "_frames";
    }
  }
  const OutputDirectory frames_output(frames_dir);
  const LoadedScene s = LoadScene(c);
  double seconds = 0.0, max_work = 0.0;
  dec::RenderStats stats;
  // An orbit of 36 views at 400x400 takes minutes: views done, time per view and ETA (#61).
  trainer::EvalProgress progress("render", int(cameras.size()));
  for (const auto& [name, camera] : cameras) {
    const auto start = std::chrono::steady_clock::now();
    dec::RenderStats view;
    const trainer::Image img = RenderDecoded(*s.field, camera, RenderOptionsFor(c), &view);
    seconds += trainer::SecondsSince(start);
    stats.Add(view);
    max_work = std::max(max_work, static_cast<double>(view.work) /
                                      (static_cast<double>(camera.width) * camera.height));
    trainer::SavePng(frames_dir + "/" + name + ".png", img);
    progress.ViewDone();
  }
  std::printf(
      "rendered %zu views into %s: %.1f ms/view (%d thread%s), decode %.1f ms, "
      "%.2f M samples/view, %.2f M MLP samples/view\n",
      cameras.size(), frames_dir.c_str(), 1e3 * seconds / std::max<size_t>(1, cameras.size()),
      RenderThreads(c), RenderThreads(c) == 1 ? "" : "s", 1e3 * s.decode_seconds,
      stats.samples / 1e6 / std::max<size_t>(1, cameras.size()),
      stats.color_samples / 1e6 / std::max<size_t>(1, cameras.size()));
  std::printf("work: %.0f multiply-adds per pixel on the costliest view (work budget %llu)\n",
              max_work, static_cast<unsigned long long>(c.render.work_budget));
  if (video.output.empty()) return 0;
  VideoJob job;
  job.frames_dir = frames_dir;
  job.frame_pattern = FramePattern(prefix);
  job.count = int(cameras.size());
  job.width = cameras[0].camera.width;
  job.height = cameras[0].camera.height;
  job.fps = video.fps;
  job.output = video.output;
  if (ffmpeg.empty()) {
    std::printf(
        "video: %s not found (%s), so %s was not written; the %d frames are in %s. To make the "
        "video, install ffmpeg (Debian: apt-get install ffmpeg) and run:\n  %s\n",
        video.ffmpeg.c_str(),
        video.ffmpeg.find('/') == std::string::npos ? "not on PATH" : "no such executable",
        video.output.c_str(), job.count, frames_dir.c_str(),
        FfmpegCommandLine(video.ffmpeg, job).c_str());
    return 0;
  }
  cleanup.Keep();  // a failed encode leaves the frames for another try (the error names them)
  const auto start = std::chrono::steady_clock::now();
  EncodeVideo(ffmpeg, job);
  const std::string kept = frames_dir == out ? "; the PNGs are in " + out : "";
  if (frames_dir != out) std::filesystem::remove_all(frames_dir);
  std::printf("wrote %s: %d frames of %dx%d at %d fps (H.264), encoded in %.1f s%s\n",
              video.output.c_str(), job.count, job.width - job.width % 2,
              job.height - job.height % 2, job.fps, trainer::SecondsSince(start), kept.c_str());
  return 0;
}

int RunEval(int argc, char** argv) {
  CommonArgs c;
  std::string data, split = "test", json_path;
  int test_stride = 1, max_test_views = 0, eval_downscale = 1, image_scale = 1;
  bool fit_exposure = false;
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
          ->check(CLI::IsMember(trainer::TypedNames<trainer::ProceduralScene>()));
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
  app->add_flag("--fit-exposure", fit_exposure,
                "the half-image protocol for captures trained with exposure codes (the file "
                "renders the neutral exposure): fit each view's gain per channel on its left half, "
                "score its right half");
  app->add_option("--json", json_path, "write the figures as JSON")->type_name("FILE");
  AddCommonFlags(app.get(), &c);
  AddRenamedFlag(app.get(), "--stride", "--test-stride");
  AddRenamedFlag(app.get(), "--downscale", "--eval-downscale");
  AddRenamedFlag(app.get(), "--max-views", "--max-test-views");
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  if (data.empty() && procedural.empty())
    return UsageError(*app, "needs --data DIR or --scene NAME");
  const LoadedScene s = LoadScene(c);
  trainer::Dataset test =
      procedural.empty()
          ? trainer::LoadDataset(data, split, eval_downscale)
          : trainer::DownscaleViews(ProceduralDataset(procedural, split, seed), eval_downscale);
  if (fit_exposure) test = trainer::WithExposureFit(std::move(test));
  const trainer::EvalResult r = EvaluateDecoded(*s.field, test, test_stride, max_test_views,
                                                RenderOptionsFor(c), false, image_scale);
  std::printf(
      "%s: %zu bytes, PSNR %.2f dB, SSIM %.4f over %d %s views of %dx%d%s; decode %.1f ms, render "
      "%.1f ms/view "
      "(%d thread%s, %s grids; %s head: %.1f samples, %.1f coloured samples per ray, %.0f k "
      "multiply-adds per pixel)\n",
      c.scene.c_str(), s.bytes.size(), r.psnr, r.ssim, r.views, split.c_str(), r.width, r.height,
      r.fitted_columns > 0 ? (" (" + trainer::HeldOutScoring(r, false) + ")").c_str() : "",
      1e3 * s.decode_seconds, 1e3 * r.seconds_per_view, RenderThreads(c),
      RenderThreads(c) == 1 ? "" : "s", c.int16 ? "int16" : "float32",
      AppearanceName(s.info.head, s.info.header.hidden), r.samples_per_ray, r.color_samples_per_ray,
      r.work_per_pixel / 1e3);
  if (!json_path.empty()) {
    nlohmann::json j = {{"scene", c.scene},
                        {"bytes", s.bytes.size()},
                        {"psnr", r.psnr},
                        {"ssim", r.ssim},
                        {"views", r.views},
                        {"width", r.width},
                        {"height", r.height},
                        {"held_out_scoring", trainer::HeldOutScoring(r, false)},
                        {"decode_seconds", s.decode_seconds},
                        {"render_seconds_per_view", r.seconds_per_view},
                        {"threads", RenderThreads(c)},
                        {"grid_storage", c.int16 ? "int16" : "float32"},
                        {"image_scale", image_scale},
                        {"downscale", eval_downscale},
                        {"samples_per_ray", r.samples_per_ray},
                        {"mlp_samples_per_ray", r.color_samples_per_ray},  // coloured
                        {"work_per_pixel", r.work_per_pixel},
                        {"head", AppearanceName(s.info.head, s.info.header.hidden)},
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
