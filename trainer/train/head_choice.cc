#include "trainer/train/head_choice.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
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

std::vector<double> PredictHeadWork(const TensorfModel& model, const RayWorkCounts& counts,
                                    const AppearanceHeadConfig* head) {
  const AppearanceHeadConfig& h = head != nullptr ? *head : model.config().head;
  dec::MlpConfig m;
  m.num_products = model.appearance().total_rank();
  m.feature_dim = h.feature_dim;
  m.feature_pe_freqs = h.feature_pe_freqs;
  m.viewdir_pe_freqs = h.viewdir_pe_freqs;
  m.hidden = h.hidden;
  m.hidden_layers = h.hidden_layers;
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

std::vector<RenderCandidate> RenderCandidates(TensorfModel* model, int n, const float* origins,
                                              const float* dirs, int sh_degree) {
  const float ratio = model->config().step_ratio;
  const int n_samples = model->n_samples();
  const AppearanceHeadConfig sh = ShHeadConfig(model->head().config(), sh_degree);
  std::vector<RenderCandidate> out, with_sh;
  for (const float r : {ratio, 2.f * ratio}) {
    if (r != ratio) model->SetStepRatio(r);
    const RayWorkCounts counts = CountRayWork(*model, n, origins, dirs);
    const std::vector<double> work = PredictHeadWork(*model, counts);
    for (int k = 0; k < kNumHeadKinds; ++k) {
      // At twice the spacing only the cheaper head: the per-sample head's spacing stays the
      // trained one (its quality is what a budget gives up first).
      if (r != ratio && HeadKind(k) == HeadKind::kPerSample) continue;
      out.push_back({HeadKind(k), r, -1, counts, work[size_t(k)]});
    }
    if (sh_degree >= 0) {
      const double w = PredictHeadWork(*model, counts, &sh)[size_t(HeadKind::kDeferred)];
      with_sh.push_back({HeadKind::kDeferred, r, sh_degree, counts, w});
    }
  }
  model->SetStepRatio(ratio);
  model->set_n_samples(n_samples);
  out.insert(out.end(), with_sh.begin(), with_sh.end());
  return out;
}

HeadChoiceReport ChooseRender(std::vector<RenderCandidate> candidates, double budget) {
  HeadChoiceReport r;
  r.budget = budget;
  r.candidates = std::move(candidates);
  if (r.candidates.empty()) throw std::logic_error("ChooseRender: no candidates");
  if (budget <= 0.0) {
    r.reason = "no render budget: the first";
    return r;
  }
  for (size_t k = 0; k < r.candidates.size(); ++k) {
    if (r.candidates[k].work <= budget) {
      r.chosen = int(k);
      r.reason = k == 0 ? "the first fits it" : "the first that fits it";
      return r;
    }
  }
  for (size_t k = 1; k < r.candidates.size(); ++k) {
    if (r.candidates[k].work < r.choice().work) r.chosen = int(k);
  }
  r.reason = "none fits it: the cheapest";
  return r;
}

namespace {

std::string Describe(const RenderCandidate& c) {
  char s[64];
  if (c.sh_degree >= 0) {
    std::snprintf(s, sizeof(s), "sh (degree %d) at step ratio %g", c.sh_degree,
                  double(c.step_ratio));
  } else {
    std::snprintf(s, sizeof(s), "%s at step ratio %g", HeadKindName(c.head), double(c.step_ratio));
  }
  return s;
}

}  // namespace

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
  HeadChoiceReport r = ChooseRender(
      RenderCandidates(s.model, n, origins.data(), dirs.data(), s.o.sh_degree), RenderBudget(s.o));
  r.iteration = it;
  const RenderCandidate& c = r.choice();
  if (c.sh_degree >= 0) {  // a head of other widths: its own initialisation and optimizer state
    AppearanceHeadConfig sh = ShHeadConfig(s.model->head().config(), c.sh_degree);
    sh.kind = c.head;
    s.model->ReplaceHead(sh, s.o.seed + 1);
    s.opt.head.Reset(s.model->head().params().size());
  }
  s.model->SetHeadKind(c.head);
  if (c.step_ratio != s.model->config().step_ratio) s.model->SetStepRatio(c.step_ratio);
  std::string predicted;
  for (const RenderCandidate& k : r.candidates) {
    char line[160];
    std::snprintf(line, sizeof(line),
                  "\n  %s: %.0f k units per pixel (%.1f samples, %.2f coloured a ray)",
                  Describe(k).c_str(), k.work / 1e3, k.counts.samples, k.counts.coloured);
    predicted += line;
  }
  std::fprintf(stderr,
               "\nhead auto at iteration %d, predicted on %d rays of the training views:%s\n"
               "  render budget %s: %s -> %s\n",
               it, n, predicted.c_str(),
               r.budget > 0 ? std::to_string(int64_t(r.budget)).c_str() : "none", r.reason.c_str(),
               Describe(c).c_str());
  s.result.head_choice = r;
}

}  // namespace trainer
}  // namespace ecrf
