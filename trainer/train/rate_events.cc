// The events of the rate objective: its start, --target-size's rate control, quantization-aware
// training and rate-distortion pruning.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "trainer/data/seconds_since.h"
#include "trainer/rate/train_rate_control.h"
#include "trainer/train/component_prune.h"
#include "trainer/train/train_events.h"

namespace ecrf {
namespace trainer {

void StartRatePhase(TrainSession& s, int it) {
  if (!s.schedule.InRatePhase(it)) return;
  const TrainOptions& o = s.o;
  if (!s.controller && o.target_bytes > 0) {
    const TensorfModel& m = *s.model;
    const size_t float_bytes =
        sizeof(float) *
        (m.density().params().size() + m.appearance().params().size() + m.head().params().size());
    s.live.lambda_e =
        o.lambda_e > 0.f ? o.lambda_e : InitialLambdaForSize(o.target_bytes, float_bytes);
    s.controller = std::make_unique<LambdaController>(o.target_bytes, s.live.lambda_e);
  }
  if (!s.rate.active) {
    s.rate.Activate(*s.model, o);
    std::fprintf(stderr, "%srate objective on at iteration %d (lambda_e %g, alpha %g)\n",
                 isatty(2) ? "\n" : "", it, s.live.lambda_e, o.alpha);
  }
}

void ControlRate(TrainSession& s, int it) {
  if (!s.controller || !s.rate.active || !s.schedule.RateControlDue(it)) return;
  const auto start = TrainClock::now();
  const size_t bytes = EncodeScene(*s.model, RunEncodeOptions(s.o, s.rate)).size();
  const double seconds = SecondsSince(start);
  const float before = s.live.lambda_e;
  s.live.lambda_e = s.controller->Update(bytes);
  s.rate.rate_control_last_bytes = s.controller->last_bytes();
  std::fprintf(stderr,
               "%srate control at iteration %d: file %zu bytes (encoded in %.2f s) for a target of "
               "%zu, lambda_e %g -> %g\n",
               isatty(2) ? "\n" : "", it, bytes, seconds, s.o.target_bytes, before,
               s.live.lambda_e);
}

void QuantizeGrids(TrainSession& s, int it) {
  if (!s.schedule.QuantAware(it)) return;
  const TrainOptions& o = s.o;
  if (!s.rate.active) s.rate.Activate(*s.model, o);  // freezes the steps (lambda_e = 0 runs)
  if (s.schedule.QatRefreshDue(it) || !s.qat.fresh_for(*s.model)) {
    if (it == s.schedule.qat_start) {
      std::fprintf(stderr, "%squantization-aware training from iteration %d\n",
                   isatty(2) ? "\n" : "", it);
    }
    s.qat.Refresh(*s.model, s.rate.steps, s.rate.config, o.mlp_levels, o.rounding_offset,
                  o.rdoq_lambda);
  }
  s.qat.Apply(s.model);
}

void PruneByRate(TrainSession& s, int it) {
  const int done = it + 1;
  if (!s.schedule.use_rate || !s.rate.active || !s.schedule.PruneDue(done)) return;
  // One pruning test (component_prune.h) on rays drawn without moving the sampler, of the model
  // as training renders it (the quantized grids under QAT, each ray at its image's exposure gain
  // when the exposure codes are on).
  const auto start = TrainClock::now();
  const TrainOptions& o = s.o;
  const float lambda_e = s.live.lambda_e;
  TensorfModel* model = s.model;
  QuantAwareModel* qat = s.schedule.QuantAware(it) ? &s.qat : nullptr;
  const int n = std::max(1, o.prune_rays);
  std::vector<float> origins(size_t(n) * 3), dirs(size_t(n) * 3), rgb(size_t(n) * 3);
  // The rays' views and gains only with exposure codes (the draws are the same either way).
  const ExposureCodes& exposure = s.progress.exposure;
  const bool exposed = exposure.enabled();
  std::vector<uint32_t> views(exposed ? size_t(n) : 0);
  std::vector<float> gains(exposed ? size_t(n) * 3 : 0);
  std::mt19937_64 rng(uint64_t(o.seed) * 0x9E3779B97F4A7C15ull + uint64_t(done));
  s.rays.Sample(n, rng, origins.data(), dirs.data(), rgb.data(), exposed ? views.data() : nullptr);
  if (exposed) exposure.Gains(n, views.data(), gains.data());
  const float* gain = exposed ? gains.data() : nullptr;
  if (qat) qat->Apply(model);
  const PruneDecision d = TestComponents(*model, s.rate, lambda_e, n, origins.data(), dirs.data(),
                                         rgb.data(), o.prune_share, gain);
  // Both tests see the same model; a component's removal leaves the hidden units as they are.
  const HiddenDecision hd = TestHiddenUnits(*model, o.mlp_levels, lambda_e, n, origins.data(),
                                            dirs.data(), rgb.data(), o.prune_share, gain);
  if (qat) qat->Restore(model);
  PruneComponents(d, model, &s.opt);  // QAT notices the new shapes and refreshes
  PruneHidden(hd, model, &s.opt);
  const auto& dr = model->density().ranks();
  const auto& ar = model->appearance().ranks();
  std::fprintf(stderr,
               "%spruning at iteration %d (lambda_e %g): %d components and %d hidden unit pairs "
               "removed; density %d,%d,%d, appearance %d,%d,%d, head %d wide remain (%.1f s)\n",
               isatty(2) ? "\n" : "", done, lambda_e, d.dropped, hd.dropped, dr[0], dr[1], dr[2],
               ar[0], ar[1], ar[2], model->head().config().hidden, SecondsSince(start));
}

}  // namespace trainer
}  // namespace ecrf
