// The events that change the field's geometry or the rays it trains on: TensoRF's alpha-mask
// updates (box shrink, ray filtering) and upsampling, and camera refinement rounds.
#include <algorithm>
#include <array>
#include <cstdio>
#include <vector>

#include "trainer/model/alpha_mask.h"
#include "trainer/train/camera_schedule.h"
#include "trainer/train/train_events.h"

namespace ecrf {
namespace trainer {
namespace {

// TensoRF's filtering_rays through the alpha mask: only rays that meet occupied space train.
void FilterRaysThroughTheMask(TrainSession& s, int it) {
  const TensorfModel& m = *s.model;
  const bool filtered = s.rays.FilterChunked(
      [&m](int count, const float* org, const float* dir, uint8_t* keep) {
        const std::vector<uint8_t> k = m.FilterRays(count, org, dir, false);
        std::copy(k.begin(), k.end(), keep);
      },
      size_t(s.o.batch_rays));
  if (filtered) {
    std::fprintf(stderr, "\nfiltered training rays: %zu of %zu remain\n", s.rays.size(),
                 s.rays.total());
  } else {
    // An empty alpha mask this early means the density has not formed yet (a very short run
    // scales the mask updates down with it); filtering would leave nothing to train on.
    std::fprintf(
        stderr,
        "\nray filtering skipped at iteration %d: the alpha mask keeps fewer rays than one "
        "batch (the model has too little density yet; more --iters give it time)\n",
        it);
  }
}

}  // namespace

void UpdateAlphaMask(TrainSession& s, int it) {
  TensorfModel* model = s.model;
  for (size_t k : s.schedule.MaskUpdatesAt(it)) {
    const Aabb new_box = model->UpdateAlphaMask(model->res());
    if (s.o.mask_downscale > 1) {
      model->SetAlphaMask(CoarsenAlphaMask(*model->alpha_mask(), s.o.mask_downscale));
    }
    if (k == 0) {
      if (!model->unbounded()) model->Shrink(new_box);  // the contracted cube is all of space
      s.progress.l1_weight = s.o.l1_weight_rest;
      s.opt.Reset(*model);
    }
    if (k == 1 && !model->unbounded() && !model->forward()) FilterRaysThroughTheMask(s, it);
  }
}

void RefreshAlphaMask(TrainSession& s) {
  TensorfModel* model = s.model;
  // A run resumed from its final checkpoint has its final mask (another pass could widen it by
  // the dilation where density lies in the last mask's margin).
  if (s.o.keep_last_mask || model->alpha_mask() == nullptr || s.first_iter >= s.o.iters) return;
  const size_t before = model->alpha_mask()->count();
  model->RefreshAlphaMask(s.o.mask_downscale);
  const std::array<int, 3>& res = model->alpha_mask()->res();
  std::fprintf(stderr,
               "alpha mask from the trained density: %zu of %zu points occupied (the last "
               "update's: %zu)\n",
               model->alpha_mask()->count(), size_t(res[0]) * res[1] * res[2], before);
}

void UpsampleGrids(TrainSession& s, int it) {
  for (size_t k : s.schedule.UpsamplesAt(it)) {
    s.model->UpsampleTo(ResolutionFor(s.schedule.voxel_counts[k], s.model->aabb()));
    s.opt.Reset(*s.model);
  }
}

void RefineCameraRound(TrainSession& s, int it) {
  const int done = it + 1;
  if (!s.schedule.cameras.Due(done)) return;
  RefineCamerasRound(done, s.schedule.cameras, *s.model, s.train.views,
                     s.exposure_on ? s.progress.exposure.log_gain().data() : nullptr,
                     s.o.seed + uint64_t(done), &s.progress.cameras, &s.result.camera_refinement);
}

}  // namespace trainer
}  // namespace ecrf
