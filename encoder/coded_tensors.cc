#include "encoder/coded_tensors.h"

#include <algorithm>
#include <cmath>

namespace ecrf {
namespace encoder {

GridBlockLayout CodedTensorLayout(const SceneHeader& header, int g, int t,
                                  const RateConfig& config) {
  const std::array<int, 3> res = {header.res[0], header.res[1], header.res[2]};
  const int rank = header.ranks[g][t % 3];
  return t < 3 ? PlaneBlockLayout(res, rank, t, config.plane_block)
               : LineBlockLayout(res, rank, t - 3, config.line_block);
}

const char* RateTensorName(int t) {
  static const char* kNames[12] = {"density.plane.0",    "density.plane.1",    "density.plane.2",
                                   "density.line.0",     "density.line.1",     "density.line.2",
                                   "appearance.plane.0", "appearance.plane.1", "appearance.plane.2",
                                   "appearance.line.0",  "appearance.line.1",  "appearance.line.2"};
  return t >= 0 && t < 12 ? kNames[t] : "?";
}

std::vector<float> PeakCoefficients(const SceneDescription& scene, const RateConfig& config) {
  std::vector<float> peaks;
  for (int g = 0; g < 2; ++g) {
    for (int t = 0; t < kTensorsPerGrid; ++t) {
      const GridBlockLayout layout = CodedTensorLayout(scene.header, g, t, config);
      std::vector<float> coeffs(layout.num_coeffs());
      ForwardBlocks(scene.tensors[g][t].data(), layout, coeffs.data());
      float peak = 0.f;
      for (float c : coeffs) peak = std::max(peak, std::fabs(c));
      peaks.push_back(peak);
    }
  }
  return peaks;
}

std::vector<float> StepsFromPeaks(std::vector<float> peaks, int coef_bits) {
  const float max_level = static_cast<float>(MaxCoefficientLevel(coef_bits));
  // An all-zero tensor still needs a positive step; any value codes it as zeros.
  for (float& s : peaks) s = s > 0.f ? s / max_level : 1.f;
  return peaks;
}

std::vector<float> ChooseQuantSteps(const SceneDescription& scene, const RateConfig& config,
                                    int coef_bits) {
  return StepsFromPeaks(PeakCoefficients(scene, config), coef_bits);
}

}  // namespace encoder
}  // namespace ecrf
