#include "trainer/train/evaluate.h"

#include <algorithm>
#include <chrono>
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

void AddViewScore(const Image& render, const View& view, EvalResult* r) {
  const int x0 = view.fitted_columns;
  double psnr = 0.0, ssim = 0.0;
  if (x0 > 0) {
    const Image scored = ColumnsFrom(render, x0), truth = ColumnsFrom(view.rgb, x0);
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
