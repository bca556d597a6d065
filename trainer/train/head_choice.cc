#include "trainer/train/head_choice.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "decoder/ray_marcher.h"
#include "decoder/render_work.h"
#include "trainer/data/camera.h"
#include "trainer/model/volume_render.h"
#include "trainer/train/train_events.h"

namespace ecrf {
namespace trainer {

RayWorkCounts CountRayWork(const TensorfModel& model, int n, const float* origins,
                           const float* dirs) {
  RayWorkCounts c;
  if (n <= 0) return c;
  // The decoder stops a ray once its transmittance is below this (SPEC.md 7.8, on by default).
  const float early_stop = dec::RenderOptions().early_stop_transmittance;
  double samples = 0.0, coloured = 0.0, coloured_rays = 0.0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : samples, coloured, coloured_rays)
  for (int r = 0; r < n; ++r) {
    int k = 0;
    float transmittance = 1.f;
    for (const RaySampleInfo& s : TraceRay(model, origins + 3 * r, dirs + 3 * r, 0.f)) {
      samples += 1.0;
      k += s.colour;
      transmittance *= 1.f - s.alpha + 1e-10f;
      if (transmittance < early_stop) break;
    }
    coloured += k;
    coloured_rays += k > 0;
  }
  c.samples = samples / n;
  c.coloured = coloured / n;
  c.coloured_rays = coloured_rays / n;
  return c;
}

std::vector<double> PredictHeadWork(const TensorfModel& model, const RayWorkCounts& counts) {
  const AppearanceHeadConfig& h = model.config().head;
  dec::MlpConfig m;
  m.num_products = model.appearance().total_rank();
  m.feature_dim = h.feature_dim;
  m.feature_pe_freqs = h.feature_pe_freqs;
  m.viewdir_pe_freqs = h.viewdir_pe_freqs;
  m.hidden = h.hidden;
  std::vector<double> work;
  for (int k = 0; k < kNumHeadKinds; ++k) {
    const dec::SampleCosts costs = dec::HeadSampleCosts(
        static_cast<HeadKind>(k), m, model.density().total_rank(), m.num_products);
    work.push_back(dec::WorkPerPixel(costs, counts.samples, counts.samples, counts.coloured,
                                     counts.coloured_rays));
  }
  return work;
}

double RenderBudget(const TrainOptions& o) {
  if (o.render_budget > 0.f) return o.render_budget;
  if (o.device_class == DeviceClassChoice::kNone) return 0.0;
  return double(dec::kDeviceClasses[int(o.device_class) - 1].work_per_pixel);
}

HeadChoiceReport ChooseHead(const TensorfModel& model, const RayWorkCounts& counts, double budget) {
  HeadChoiceReport r;
  r.budget = budget;
  r.counts = counts;
  r.work = PredictHeadWork(model, counts);
  const double mlp = r.work[int(HeadKind::kPerSample)];
  const double deferred = r.work[int(HeadKind::kDeferred)];
  char why[160];
  if (budget <= 0.0) {
    r.chosen = HeadKind::kPerSample;
    std::snprintf(why, sizeof(why), "no render budget, the per-sample head");
  } else if (mlp <= budget) {
    r.chosen = HeadKind::kPerSample;
    std::snprintf(why, sizeof(why), "the per-sample head fits it");
  } else {
    r.chosen = HeadKind::kDeferred;
    std::snprintf(why, sizeof(why), "the per-sample head exceeds it, the deferred head %s",
                  deferred <= budget ? "fits it" : "is the cheaper (still over it)");
  }
  r.reason = why;
  return r;
}

void ChooseHeadIfAuto(TrainSession& s, int it) {
  if (s.o.head != HeadChoice::kAuto || it != s.schedule.grid_final) return;
  // Whole views, background included, as a viewer renders them: every k-th pixel of up to four
  // training views spread over the set (the test views are not looked at).
  constexpr int kViews = 4, kRaysPerView = 4096;
  std::vector<float> origins, dirs;
  const size_t n_views = s.train.views.size();
  for (size_t k = 0; k < std::min<size_t>(kViews, n_views); ++k) {
    const Camera& cam = s.train.views[k * n_views / std::min<size_t>(kViews, n_views)].camera;
    std::vector<float> o, d;
    GenerateRowRays(cam, 0, cam.height, &o, &d);
    const size_t pixels = o.size() / 3;
    const size_t step = std::max<size_t>(1, pixels / kRaysPerView);
    for (size_t p = 0; p < pixels; p += step) {
      origins.insert(origins.end(), o.begin() + 3 * p, o.begin() + 3 * p + 3);
      dirs.insert(dirs.end(), d.begin() + 3 * p, d.begin() + 3 * p + 3);
    }
  }
  const int n = int(origins.size() / 3);
  HeadChoiceReport r = ChooseHead(*s.model, CountRayWork(*s.model, n, origins.data(), dirs.data()),
                                  RenderBudget(s.o));
  r.iteration = it;
  s.model->SetHeadKind(r.chosen);
  std::fprintf(stderr,
               "\nhead auto at iteration %d: predicted work per pixel %.0f k (mlp), %.0f k "
               "(deferred) from %.1f samples and %.2f coloured samples a ray on %d rays of the "
               "training views; render budget %s: %s -> %s\n",
               it, r.work[int(HeadKind::kPerSample)] / 1e3, r.work[int(HeadKind::kDeferred)] / 1e3,
               r.counts.samples, r.counts.coloured, n,
               r.budget > 0 ? std::to_string(int64_t(r.budget)).c_str() : "none", r.reason.c_str(),
               HeadKindName(r.chosen));
  s.result.head_choice = r;
}

}  // namespace trainer
}  // namespace ecrf
