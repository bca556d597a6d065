#include "encoder/coded_tensors.h"

#include <algorithm>
#include <cmath>

namespace ecrf {
namespace trainer {

GridBlockLayout RateTensorLayout(const VmGrid& grid, int t, const RateConfig& config) {
  return t < 3 ? PlaneBlockLayout(grid, t, config.plane_block)
               : LineBlockLayout(grid, t - 3, config.line_block);
}

const float* RateTensorData(const VmGrid& grid, int t) {
  return t < 3 ? grid.plane(t) : grid.line(t - 3);
}

float* RateTensorGrad(VmGrid& grid, int t) {
  return t < 3 ? grid.plane_grad(t) : grid.line_grad(t - 3);
}

const char* RateTensorName(int t) {
  static const char* kNames[12] = {"density.plane.0",    "density.plane.1",    "density.plane.2",
                                   "density.line.0",     "density.line.1",     "density.line.2",
                                   "appearance.plane.0", "appearance.plane.1", "appearance.plane.2",
                                   "appearance.line.0",  "appearance.line.1",  "appearance.line.2"};
  return t >= 0 && t < 12 ? kNames[t] : "?";
}

std::vector<float> PeakCoefficients(const TensorfModel& model, const RateConfig& config) {
  std::vector<float> peaks;
  for (const VmGrid* grid : {&model.density(), &model.appearance()}) {
    for (int t = 0; t < kTensorsPerGrid; ++t) {
      const GridBlockLayout layout = RateTensorLayout(*grid, t, config);
      std::vector<float> coeffs(layout.num_coeffs());
      ForwardBlocks(RateTensorData(*grid, t), layout, coeffs.data());
      float peak = 0.f;
      for (float c : coeffs) peak = std::max(peak, std::fabs(c));
      peaks.push_back(peak);
    }
  }
  return peaks;
}

std::vector<float> ChooseQuantSteps(const TensorfModel& model, const RateConfig& config,
                                    int coef_bits) {
  const float max_level = coef_bits == 16 ? 32767.f : 127.f;
  std::vector<float> steps = PeakCoefficients(model, config);
  // An all-zero tensor still needs a positive step; any value codes it as zeros.
  for (float& s : steps) s = s > 0.f ? s / max_level : 1.f;
  return steps;
}

}  // namespace trainer
}  // namespace ecrf
