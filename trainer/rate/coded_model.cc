#include "trainer/rate/coded_model.h"

#include <algorithm>

namespace ecrf {
namespace trainer {

encoder::SceneDescription DescribeModel(const TensorfModel& model) {
  encoder::SceneDescription s;
  SceneHeader& h = s.header;
  const TensorfConfig& c = model.config();
  // Unbounded: HEAD carries the region of interest; the grids span the contracted cube.
  const Aabb& box = model.unbounded() ? c.roi : model.aabb();
  h.scene_model = static_cast<uint8_t>(c.scene_model);
  s.ndc = c.ndc;
  for (int a = 0; a < 3; ++a) {
    h.aabb_min[a] = box.min[a];
    h.aabb_max[a] = box.max[a];
    h.res[a] = static_cast<uint16_t>(model.res()[a]);
  }
  const VmGrid* grids[2] = {&model.density(), &model.appearance()};
  for (int g = 0; g < 2; ++g) {
    for (int m = 0; m < 3; ++m) {
      h.ranks[g][m] = static_cast<uint16_t>(grids[g]->ranks()[m]);
      s.tensors[g][m].assign(grids[g]->plane(m), grids[g]->plane(m) + grids[g]->plane_size(m));
      s.tensors[g][3 + m].assign(grids[g]->line(m), grids[g]->line(m) + grids[g]->line_size(m));
    }
  }
  h.density_shift = c.density_shift;
  h.density_activation = static_cast<uint8_t>(c.density_activation);
  h.distance_scale = c.distance_scale;
  h.step_size = model.step_size();
  h.num_samples = static_cast<uint32_t>(std::max(1, model.n_samples()));
  h.weight_threshold = c.weight_threshold;
  h.near_far[0] = c.near;
  h.near_far[1] = c.far;
  for (float& b : h.background) b = c.white_background ? 1.f : 0.f;
  const AppearanceHeadConfig& hc = model.head().config();
  h.feature_dim = static_cast<uint16_t>(hc.feature_dim);
  h.feature_pe_freqs = static_cast<uint8_t>(hc.feature_pe_freqs);
  h.viewdir_pe_freqs = static_cast<uint8_t>(hc.viewdir_pe_freqs);
  h.hidden = static_cast<uint16_t>(hc.hidden);
  s.head_params = model.head().params();
  s.head = model.config().head.kind;
  s.mlp_hidden_layers = hc.hidden_layers;
  if (const AlphaMask* mask = model.alpha_mask()) {
    encoder::OccupancyDescription& occupancy = s.mask.emplace();
    occupancy.aabb_min = mask->aabb().min;
    occupancy.aabb_max = mask->aabb().max;
    occupancy.res = mask->res();
    occupancy.occupancy = mask->occupancy();
  }
  return s;
}

encoder::GridBlockLayout RateTensorLayout(const VmGrid& grid, int t,
                                          const encoder::RateConfig& config) {
  return t < 3
             ? encoder::PlaneBlockLayout(grid.res(), grid.ranks()[t], t, config.plane_block)
             : encoder::LineBlockLayout(grid.res(), grid.ranks()[t - 3], t - 3, config.line_block);
}

const float* RateTensorData(const VmGrid& grid, int t) {
  return t < 3 ? grid.plane(t) : grid.line(t - 3);
}

float* RateTensorGrad(VmGrid& grid, int t) {
  return t < 3 ? grid.plane_grad(t) : grid.line_grad(t - 3);
}

std::vector<uint8_t> EncodeScene(const TensorfModel& model, const encoder::EncodeOptions& options,
                                 encoder::EncodeReport* report) {
  return encoder::EncodeScene(DescribeModel(model), options, report);
}

encoder::TargetSizeResult EncodeToTargetSize(const TensorfModel& model,
                                             const encoder::EncodeOptions& options,
                                             size_t target_bytes) {
  return encoder::EncodeToTargetSize(DescribeModel(model), options, target_bytes);
}

std::vector<float> ChooseQuantSteps(const TensorfModel& model, const encoder::RateConfig& config,
                                    int coef_bits) {
  return encoder::ChooseQuantSteps(DescribeModel(model), config, coef_bits);
}

}  // namespace trainer
}  // namespace ecrf
