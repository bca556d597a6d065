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

EvalResult Evaluate(const TensorfModel& model, const Dataset& test, int stride, int max_views,
                    bool keep_renders) {
  EvalResult r;
  const auto start = std::chrono::steady_clock::now();
  const std::vector<size_t> views = EvalViews(test.views.size(), stride, max_views);
  EvalProgress progress("evaluating the float model", int(views.size()));
  for (const size_t v : views) {
    Image img = RenderView(model, test.views[v].camera);
    // The half-image protocol: columns that fitted the view's camera are not scored.
    const int x0 = test.views[v].fitted_columns;
    const Image scored = ColumnsFrom(img, x0), truth = ColumnsFrom(test.views[v].rgb, x0);
    // A view rendered exactly has infinite PSNR; cap it so one such view cannot swamp the mean.
    r.psnr += std::min(100.0, Psnr(scored, truth));
    r.ssim += Ssim(scored, truth);
    r.fitted_columns = std::max(r.fitted_columns, x0);
    if (r.views++ == 0) {
      r.width = img.width;
      r.height = img.height;
    }
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
