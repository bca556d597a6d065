#include "tools/decoded_scene.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "trainer/data/camera.h"
#include "trainer/data/file_io.h"
#include "trainer/data/image_metrics.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/eval_progress.h"

namespace ecrf {
namespace tools {
LoadedScene DecodeSceneBytes(std::vector<uint8_t> bytes, const std::string& name,
                             dec::GridStorage storage, uint64_t max_memory_bytes,
                             uint64_t work_per_byte) {
  LoadedScene s;
  s.bytes = std::move(bytes);
  s.field = std::make_unique<dec::SceneField>();
  dec::DecodeOptions options;
  options.storage = storage;
  options.max_memory_bytes = max_memory_bytes;
  options.work_per_byte = work_per_byte;
  const auto start = std::chrono::steady_clock::now();
  const Status st =
      dec::DecodeScene(s.bytes.data(), s.bytes.size(), options, s.field.get(), &s.info);
  s.decode_seconds = trainer::SecondsSince(start);
  if (!st.ok()) {
    throw std::runtime_error(name + ": cannot decode (" + ErrorCodeName(st.code()) +
                             "): " + st.message());
  }
  return s;
}

LoadedScene LoadSceneFile(const std::string& path, dec::GridStorage storage,
                          uint64_t max_memory_bytes, uint64_t work_per_byte) {
  return DecodeSceneBytes(trainer::ReadWholeFile(path), path, storage, max_memory_bytes,
                          work_per_byte);
}

trainer::Image RenderDecoded(const dec::SceneField& scene, const trainer::Camera& camera,
                             const dec::RenderOptions& options, dec::RenderStats* stats) {
  dec::RayMarcher marcher;
  Status st = marcher.Init(&scene, options);
  if (!st.ok()) throw std::runtime_error(std::string("renderer: ") + st.message());
  trainer::Image img;
  img.width = camera.width;
  img.height = camera.height;
  img.channels = 3;
  img.pixels.resize(size_t(img.width) * img.height * 3);
  const int rows_per_chunk = std::max(1, 65536 / std::max(1, camera.width));
  // Bands of rows, one work budget for the whole view (SPEC.md 8.2).
  marcher.BeginView(uint64_t(camera.width) * uint64_t(camera.height));
  std::vector<float> origins, dirs;
  for (int y0 = 0; y0 < camera.height; y0 += rows_per_chunk) {
    const int rows = std::min(rows_per_chunk, camera.height - y0);
    const size_t n = size_t(rows) * camera.width;
    trainer::GenerateRowRays(camera, y0, rows, &origins, &dirs);
    dec::RenderStats chunk_stats;
    st = marcher.RenderRays(n, origins.data(), dirs.data(),
                            &img.pixels[size_t(y0) * camera.width * 3], nullptr, &chunk_stats);
    if (!st.ok()) throw std::runtime_error(std::string("renderer: ") + st.message());
    if (stats) stats->Add(chunk_stats);
  }
  return img;
}

bool IsProceduralScene(const std::string& name) {
  const std::vector<std::string> names = trainer::TypedNames<trainer::ProceduralScene>();
  return std::find(names.begin(), names.end(), name) != names.end();
}

trainer::Dataset ProceduralDataset(const std::string& scene, const std::string& split,
                                   uint32_t seed) {
  trainer::TrainOptions o = trainer::PresetOptions("tiny");
  o.procedural_scene = trainer::ChoiceFromName<trainer::ProceduralScene>(scene, "scene");
  o.seed = seed;
  return trainer::LoadTrainingViews(o, split);
}

trainer::Image ResizeBilinear(const trainer::Image& image, int width, int height) {
  trainer::Image out = trainer::MakeImage(width, height, image.channels);
  const int c = image.channels;
  const float sx = float(image.width) / width, sy = float(image.height) / height;
  for (int y = 0; y < height; ++y) {
    const float fy = std::clamp((y + 0.5f) * sy - 0.5f, 0.f, float(image.height - 1));
    const int y0 = int(fy), y1 = std::min(y0 + 1, image.height - 1);
    const float wy = fy - y0;
    for (int x = 0; x < width; ++x) {
      const float fx = std::clamp((x + 0.5f) * sx - 0.5f, 0.f, float(image.width - 1));
      const int x0 = int(fx), x1 = std::min(x0 + 1, image.width - 1);
      const float wx = fx - x0;
      for (int k = 0; k < c; ++k) {
        auto at = [&](int yy, int xx) {
          return image.pixels[(size_t(yy) * image.width + xx) * c + k];
        };
        const float top = at(y0, x0) + (at(y0, x1) - at(y0, x0)) * wx;
        const float bottom = at(y1, x0) + (at(y1, x1) - at(y1, x0)) * wx;
        out.pixels[(size_t(y) * width + x) * c + k] = top + (bottom - top) * wy;
      }
    }
  }
  return out;
}

trainer::EvalResult EvaluateDecoded(const dec::SceneField& scene, const trainer::Dataset& test,
                                    int stride, int max_views, const dec::RenderOptions& options,
                                    bool keep_renders, int image_scale, dec::RenderStats* stats) {
  trainer::EvalResult r;
  double render_seconds = 0.0;
  image_scale = std::max(1, image_scale);
  dec::RenderStats all;
  const std::vector<size_t> views = trainer::EvalViews(test.views.size(), stride, max_views);
  trainer::EvalProgress progress("evaluating the decoded file", int(views.size()));
  for (const size_t v : views) {
    trainer::Camera camera = test.views[v].camera;
    if (image_scale > 1) {
      camera.width = std::max(1, camera.width / image_scale);
      camera.height = std::max(1, camera.height / image_scale);
      const double kx = double(camera.width) / test.views[v].camera.width;
      const double ky = double(camera.height) / test.views[v].camera.height;
      camera.fx *= kx;
      camera.cx *= kx;
      camera.fy *= ky;
      camera.cy *= ky;
    }
    const auto start = std::chrono::steady_clock::now();
    trainer::Image img = RenderDecoded(scene, camera, options, &all);
    render_seconds += trainer::SecondsSince(start);
    if (image_scale > 1)
      img = ResizeBilinear(img, test.views[v].rgb.width, test.views[v].rgb.height);
    trainer::AddViewScore(img, test.views[v], &r);
    if (keep_renders) r.renders.push_back(std::move(img));
    char extra[96];
    std::snprintf(extra, sizeof(extra), "%.1f samples and %.1f coloured samples per ray",
                  double(all.samples) / double(std::max<uint64_t>(1, all.rays)),
                  double(all.color_samples) / double(std::max<uint64_t>(1, all.rays)));
    progress.ViewDone(extra);
  }
  if (r.views > 0) {
    r.psnr /= r.views;
    r.ssim /= r.views;
    r.seconds_per_view = render_seconds / r.views;
  }
  if (all.rays > 0) {
    r.samples_per_ray = double(all.samples) / double(all.rays);
    r.color_samples_per_ray = double(all.color_samples) / double(all.rays);
    r.work_per_pixel = double(all.work) / double(all.rays);
  }
  if (stats) stats->Add(all);
  return r;
}

}  // namespace tools
}  // namespace ecrf
