// The encoder: a scene description (encoder/scene_description.h) -> an .ecrf stream (SPEC.md
// section 6).
//
// Per feature tensor: block DCT (the blocks and edge padding of training, encoder/grid_dct.h) ->
// uniform quantization with the tensor's step -> the context-modelled coefficient coder ->
// one COEF chunk. Plus HEAD (geometry, ranks, render parameters), OCCU (the alpha mask) and MLPW
// (basis and MLP weights, float16 by default).
//
// Only what the scene needs is coded: a rank component whose plane or line decodes to exactly
// zero contributes nothing, so the encoder decodes its own first pass, drops such components
// (with their basis columns) and codes the smaller model; all-zero blocks cost one well-predicted
// symbol; the grids cover only the shrunk box.
#ifndef ECRF_ENCODER_SCENE_ENCODER_H_
#define ECRF_ENCODER_SCENE_ENCODER_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "encoder/coded_tensors.h"
#include "encoder/scene_description.h"
#include "format/container.h"

namespace ecrf {
namespace encoder {

struct EncodeOptions {
  int coef_bits = 8;         // 8 or 16
  bool mlp_float32 = false;  // false: float16 weights
  // > 0: the MLP and basis as integer levels with one binary16 step per output row, the largest
  // level of a row being this (MLPW precision 2, bitstream 1.1); overrides mlp_float32.
  int mlp_max_level = 0;
  bool drop_zero_components = true;
  bool include_occupancy = true;  // the occupancy mask, when the scene has one
  RateConfig blocks;              // plane and line block shapes
  // One step per tensor (density planes 0..2, lines 0..2, then appearance), e.g. the steps the
  // rate objective froze in training; empty: ChooseQuantSteps (largest coefficient -> max level).
  std::vector<float> steps;
  // Rounding offset of the coefficient quantizer (encoder/coef_quantizer.h): 0.5 rounds to
  // nearest, smaller values widen the dead zone.
  float rounding_offset = 0.5f;
  // > 0: rate-distortion optimised quantization (encoder/coef_rdoq.h) with this lambda, in
  // squared steps per bit; 0: the rounding alone.
  float rdoq_lambda = 0.f;
  std::string metadata_json;  // the ancillary meta chunk (empty: none)
  // The newest stream version 1.x to write. From 4 on, each COEF chunk takes the shorter of its
  // narrow and wide (1.4) codes; below 4 all are narrow, so 1.3 decoders read the stream (2-3.5%
  // larger coefficient chunks). The stream carries the lowest version its chunks need.
  int max_version_minor = kVersionMinor;
};

struct EncodeReport {
  size_t total_bytes = 0;
  size_t head_bytes = 0, occupancy_bytes = 0, mlp_bytes = 0,
         metadata_bytes = 0;               // head: HEAD and NDCP
  size_t container_bytes = 0;              // signature, chunk headers and CRCs
  std::array<size_t, 12> tensor_bytes{};   // COEF payload per tensor (0 when dropped)
  std::array<size_t, 12> tensor_coeffs{};  // coefficients per tensor (padded blocks)
  std::array<size_t, 12> tensor_blocks{};
  std::array<size_t, 12> tensor_zero_blocks{};
  std::array<float, 12> steps{};
  std::array<std::array<int, 3>, 2> ranks_in{};   // before dropping
  std::array<std::array<int, 3>, 2> ranks_out{};  // coded
  size_t clipped_coefficients = 0;                // magnitudes above the coefficient range, clamped
  size_t coefficient_bytes() const {
    size_t n = 0;
    for (size_t b : tensor_bytes) n += b;
    return n;
  }
};

// Throws std::invalid_argument for impossible options or a description whose arrays do not have
// the sizes its header gives them, and std::runtime_error if the encoder's own decode check fails.
std::vector<uint8_t> EncodeScene(const SceneDescription& scene, const EncodeOptions& options,
                                 EncodeReport* report = nullptr);

}  // namespace encoder
}  // namespace ecrf

#endif  // ECRF_ENCODER_SCENE_ENCODER_H_
