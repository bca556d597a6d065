// Trains the built-in procedural scene for a few iterations with the trainer API, encodes the
// model to memory, decodes those bytes with the C API and scores the decoded scene on the test
// views (what `ecrf train --scene builtin` does, in a few lines).
//
//   train_encode [iterations]     (default 200: about half a minute on 2 cores)
#include <ecrf/decoder.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <vector>

#include "trainer/train/trainer.h"

namespace tr = ecrf::trainer;

// PSNR of the decoder's float RGB against one test view (both in [0, 1]).
static double DecodedPsnr(ecrf_scene* scene, const tr::View& view) {
  const tr::Camera& c = view.camera;
  ecrf_camera cam;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 4; ++k) cam.c2w[4 * r + k] = static_cast<float>(c.c2w[r][k]);
  cam.fx = static_cast<float>(c.fx);
  cam.fy = static_cast<float>(c.fy);
  cam.cx = static_cast<float>(c.cx);
  cam.cy = static_cast<float>(c.cy);
  cam.width = c.width;
  cam.height = c.height;
  ecrf_render_options options;
  ecrf_render_options_default(&options);
  options.num_threads = 0;
  std::vector<float> rgb(static_cast<size_t>(c.width) * c.height * 3);
  if (ecrf_scene_render(scene, &cam, &options, nullptr, rgb.data()) < 0) {
    std::fprintf(stderr, "render: %s\n", ecrf_scene_message(scene));
    return -1.0;
  }
  double se = 0.0;
  for (size_t i = 0; i < rgb.size(); ++i) {
    const double d = rgb[i] - view.rgb.pixels[i];
    se += d * d;
  }
  return -10.0 * std::log10(se / static_cast<double>(rgb.size()));
}

int main(int argc, char** argv) {
  try {
    tr::TrainOptions o = tr::PresetOptions("tiny");
    o.procedural_scene = tr::ProceduralScene::kBuiltin;
    o.iters = argc > 1 ? std::atoi(argv[1]) : 200;
    if (o.iters < 1) {
      std::fprintf(stderr, "usage: %s [iterations]\n", argv[0]);
      return 2;
    }
    const tr::Dataset train = tr::LoadTrainingViews(o, "train");
    const tr::Dataset test = tr::LoadTrainingViews(o, "test");
    tr::TensorfModel model(tr::ConfigFor(o, train));
    tr::RateState rate;
    const tr::TrainResult r = tr::Train(o, train, test, &model, &rate);
    std::printf("trained %d iterations in %.1f s: test PSNR %.2f dB (float model)\n", r.iterations,
                r.train_seconds, r.test.psnr);

    ecrf::encoder::EncodeReport report;
    const std::vector<uint8_t> bytes =
        tr::EncodeScene(model, tr::RunEncodeOptions(o, rate), &report);

    ecrf_scene* scene = ecrf_scene_create();
    if (!scene) return 1;
    if (ecrf_scene_decode(scene, bytes.data(), bytes.size(), ECRF_STORAGE_FLOAT32) < 0) {
      std::fprintf(stderr, "decode: %s\n", ecrf_scene_message(scene));
      ecrf_scene_destroy(scene);
      return 1;
    }
    double psnr = 0.0;
    for (const tr::View& view : test.views) psnr += DecodedPsnr(scene, view);
    psnr /= static_cast<double>(test.views.size());
    ecrf_scene_destroy(scene);
    std::printf(
        "encoded %zu bytes (coefficients %zu); decoded with ecrf %s: test PSNR %.2f dB over %zu "
        "views\n",
        bytes.size(), report.coefficient_bytes(), ecrf_version_string(), psnr, test.views.size());
    return psnr > 0.0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
