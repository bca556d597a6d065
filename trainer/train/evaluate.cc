#include "trainer/train/evaluate.h"

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "trainer/data/camera.h"
#include "trainer/data/image_metrics.h"
#include "trainer/model/volume_render.h"
#include "trainer/train/eval_progress.h"

namespace ecrf {
namespace trainer {
Image RenderView(const TensorfModel& model, const Camera& camera) {
  Image img;
  img.width = camera.width;
  img.height = camera.height;
  img.channels = 3;
  img.pixels.resize(size_t(img.width) * img.height * 3);
  const int rows_per_chunk = std::max(1, 16384 / std::max(1, camera.width));
  std::vector<float> origins, dirs;
  for (int y0 = 0; y0 < camera.height; y0 += rows_per_chunk) {
    const int rows = std::min(rows_per_chunk, camera.height - y0);
    const int n = rows * camera.width;
    GenerateRowRays(camera, y0, rows, &origins, &dirs);
    RenderRays(model, n, origins.data(), dirs.data(), &img.pixels[size_t(y0) * camera.width * 3],
               nullptr);
  }
  return img;
}

void FitExposureGain(const Image& render, const Image& truth, int x1, float gain[3]) {
  double rt[3] = {0, 0, 0}, rr[3] = {0, 0, 0};
  x1 = std::min(x1, std::min(render.width, truth.width));
  for (int y = 0; y < std::min(render.height, truth.height); ++y) {
    for (int x = 0; x < x1; ++x) {
      for (int c = 0; c < 3; ++c) {
        const double r = render.pixels[(size_t(y) * render.width + x) * render.channels + c];
        const double t = truth.pixels[(size_t(y) * truth.width + x) * truth.channels + c];
        rt[c] += r * t;
        rr[c] += r * r;
      }
    }
  }
  for (int c = 0; c < 3; ++c) gain[c] = rr[c] > 0 ? float(rt[c] / rr[c]) : 1.f;
}

Dataset WithExposureFit(Dataset data) {
  for (View& v : data.views) {
    v.fit_exposure = true;
    v.fitted_columns = std::max(v.fitted_columns, v.rgb.width / 2);
  }
  return data;
}

std::string HeldOutScoring(const EvalResult& r, bool cameras_aligned) {
  if (r.fitted_columns == 0) return "whole views";
  const char* fitted = !r.exposure_fitted ? "cameras aligned"
                       : cameras_aligned  ? "cameras aligned and exposure gains fitted"
                                          : "exposure gains fitted";
  return std::string("right halves; ") + fitted + " on the left halves";
}

void AddViewScore(const Image& render, const View& view, EvalResult* r) {
  const int x0 = view.fitted_columns;
  double psnr = 0.0, ssim = 0.0;
  if (x0 > 0) {
    Image scored = ColumnsFrom(render, x0);
    const Image truth = ColumnsFrom(view.rgb, x0);
    if (view.fit_exposure) {
      float gain[3];
      FitExposureGain(render, view.rgb, x0, gain);
      for (size_t i = 0; i < scored.pixels.size(); ++i) {
        const int c = int(i % size_t(scored.channels));
        if (c < 3) scored.pixels[i] = std::min(1.f, gain[c] * scored.pixels[i]);
      }
      r->exposure_fitted = true;
    }
    psnr = Psnr(scored, truth);
    ssim = Ssim(scored, truth);
  } else {
    psnr = Psnr(render, view.rgb);
    ssim = Ssim(render, view.rgb);
  }
  // A view rendered exactly has infinite PSNR; cap it so one such view cannot swamp the mean.
  r->psnr += std::min(100.0, psnr);
  r->ssim += ssim;
  r->fitted_columns = std::max(r->fitted_columns, x0);
  if (r->views++ == 0) {
    r->width = render.width;
    r->height = render.height;
  }
}

EvalResult Evaluate(const TensorfModel& model, const Dataset& test, int stride, int max_views,
                    bool keep_renders) {
  EvalResult r;
  const auto start = std::chrono::steady_clock::now();
  const std::vector<size_t> views = EvalViews(test.views.size(), stride, max_views);
  EvalProgress progress("evaluating the float model", int(views.size()));
  for (const size_t v : views) {
    Image img = RenderView(model, test.views[v].camera);
    AddViewScore(img, test.views[v], &r);
    if (keep_renders) r.renders.push_back(std::move(img));
    progress.ViewDone();
  }
  if (r.views > 0) {
    r.psnr /= r.views;
    r.ssim /= r.views;
    r.seconds_per_view = SecondsSince(start) / r.views;
  }
  return r;
}

}  // namespace trainer
}  // namespace ecrf
