// The trainer's renderer against the decoder's on one decoded field: the tests of each scene
// model load the decoded grids into the trainer's model and render the same rays both ways.
#ifndef ECRF_TESTS_COMMON_RENDERER_AGREEMENT_H_
#define ECRF_TESTS_COMMON_RENDERER_AGREEMENT_H_

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/model/volume_render.h"

namespace ecrf {
namespace trainer {

// Copies the decoded grids into the model so that both renderers see the same values.
inline void LoadDecodedGrids(const dec::SceneField& field, TensorfModel* model) {
  VmGrid* grids[2] = {&model->density(), &model->appearance()};
  const dec::VmGrid* decoded[2] = {&field.density, &field.appearance};
  for (int g = 0; g < 2; ++g) {
    for (int m = 0; m < 3; ++m) {
      std::copy(decoded[g]->plane_f32[m].data(),
                decoded[g]->plane_f32[m].data() + grids[g]->plane_size(m), grids[g]->plane(m));
      std::copy(decoded[g]->line_f32[m].data(),
                decoded[g]->line_f32[m].data() + grids[g]->line_size(m), grids[g]->line(m));
    }
  }
}

struct RendererAgreement {
  float worst = 0.f;   // largest difference of a channel between the two renderers
  float spread = 0.f;  // largest difference of a channel from the first ray's (the rays differ)
  uint64_t decoder_samples = 0;
};

// Renders the rays with RenderRays and with the decoder's reference process (no early stop).
inline RendererAgreement RenderBothWays(const TensorfModel& model, const dec::SceneField& field,
                                        const std::vector<float>& origins,
                                        const std::vector<float>& dirs) {
  RendererAgreement r;
  const size_t n = origins.size() / 3;
  std::vector<float> mine(n * 3), theirs(n * 3), acc(n);
  RenderRays(model, int(n), origins.data(), dirs.data(), mine.data(), nullptr);
  dec::RenderOptions ro;
  ro.early_stop_transmittance = 0.f;
  dec::RayMarcher marcher;
  EXPECT_TRUE(marcher.Init(&field, ro).ok());
  dec::RenderStats stats;
  EXPECT_TRUE(
      marcher.RenderRays(n, origins.data(), dirs.data(), theirs.data(), acc.data(), &stats).ok());
  for (size_t i = 0; i < mine.size(); ++i) {
    r.worst = std::max(r.worst, std::fabs(mine[i] - theirs[i]));
    r.spread = std::max(r.spread, std::fabs(theirs[i] - theirs[0]));
  }
  r.decoder_samples = stats.samples;
  return r;
}

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_RENDERER_AGREEMENT_H_
