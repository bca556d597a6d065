// The coded tensors of a scene: each VM grid (density, then appearance) has six, planes 0..2
// then lines 0..2, coded in that order (tensor index = grid * 6 + t, SPEC.md 4.3). Their block
// shapes, layouts, names, and the quantization steps that map each tensor's largest block-DCT
// coefficient to the largest level. Shared by the encoder and the rate objective that trains
// for it, so that the trained rate is the rate of the file.
#ifndef ECRF_ENCODER_CODED_TENSORS_H_
#define ECRF_ENCODER_CODED_TENSORS_H_

#include <cstdint>
#include <vector>

#include "encoder/grid_dct.h"
#include "encoder/scene_description.h"
#include "format/scene_header.h"

namespace ecrf {
namespace encoder {

inline constexpr int kTensorsPerGrid = 6;

// The block shapes of the DCT, chosen at training time and written to the stream.
struct RateConfig {
  int plane_block[3] = {16, 16, 16};  // channel x H x W
  int line_block[3] = {1, 8, 8};      // 1 x channel x L
};

// Block layout of tensor t (0..5) of grid g with the header's resolution and ranks.
GridBlockLayout CodedTensorLayout(const SceneHeader& header, int g, int t,
                                  const RateConfig& config);

// The largest quantization level of a coefficient coded in coef_bits bits (8 or 16; SPEC.md's
// coefficient range): 127 or 32767.
inline int32_t MaxCoefficientLevel(int coef_bits) { return coef_bits == 16 ? 32767 : 127; }

// Quantization step of each tensor for coef_bits-bit coefficients: the largest magnitude of its
// block-DCT coefficients maps to the largest level (127 for 8 bits), so nothing clips. The
// encoder uses this rule when the rate objective was off.
std::vector<float> ChooseQuantSteps(const SceneDescription& scene, const RateConfig& config,
                                    int coef_bits);
// The largest block-DCT coefficient magnitude of each tensor (0 for an all-zero tensor), in the
// order of ChooseQuantSteps.
std::vector<float> PeakCoefficients(const SceneDescription& scene, const RateConfig& config);
// ChooseQuantSteps' rule applied to peaks already computed: peak / max level, 1 for a zero peak.
std::vector<float> StepsFromPeaks(std::vector<float> peaks, int coef_bits);

// Name of tensor index t (0..11) as in checkpoints: "density.plane.0" ... "appearance.line.2".
const char* RateTensorName(int t);

}  // namespace encoder
}  // namespace ecrf

#endif  // ECRF_ENCODER_CODED_TENSORS_H_
