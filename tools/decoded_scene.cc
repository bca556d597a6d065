#include "tools/decoded_scene.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "trainer/camera.h"
#include "trainer/checkpoint.h"
#include "trainer/image_metrics.h"

namespace ecrf {
namespace tools {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

LoadedScene DecodeSceneBytes(std::vector<uint8_t> bytes, const std::string& name,
                             dec::GridStorage storage) {
  LoadedScene s;
  s.bytes = std::move(bytes);
  s.field = std::make_unique<dec::SceneField>();
  dec::DecodeOptions options;
  options.storage = storage;
  const auto start = std::chrono::steady_clock::now();
  const Status st = dec::DecodeScene(s.bytes.data(), s.bytes.size(), options, s.field.get(), &s.info);
  s.decode_seconds = SecondsSince(start);
  if (!st.ok()) {
    throw std::runtime_error(name + ": cannot decode (" + ErrorCodeName(st.code()) + "): " + st.message());
  }
  return s;
}

LoadedScene LoadSceneFile(const std::string& path, dec::GridStorage storage) {
  return DecodeSceneBytes(trainer::ReadWholeFile(path), path, storage);
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

trainer::EvalResult EvaluateDecoded(const dec::SceneField& scene, const trainer::Dataset& test,
                                    int stride, int max_views, const dec::RenderOptions& options,
                                    bool keep_renders) {
  trainer::EvalResult r;
  double render_seconds = 0.0;
  stride = std::max(1, stride);
  for (size_t v = 0; v < test.views.size(); v += size_t(stride)) {
    if (max_views > 0 && r.views >= max_views) break;
    const auto start = std::chrono::steady_clock::now();
    trainer::Image img = RenderDecoded(scene, test.views[v].camera, options);
    render_seconds += SecondsSince(start);
    r.psnr += std::min(100.0, trainer::Psnr(img, test.views[v].rgb));
    r.ssim += trainer::Ssim(img, test.views[v].rgb);
    ++r.views;
    if (keep_renders) r.renders.push_back(std::move(img));
  }
  if (r.views > 0) {
    r.psnr /= r.views;
    r.ssim /= r.views;
    r.seconds_per_view = render_seconds / r.views;
  }
  return r;
}

}  // namespace tools
}  // namespace ecrf
