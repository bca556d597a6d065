// A scene as the encoder codes it (SPEC.md 6), in the stream's own terms: the HEAD fields, the
// twelve feature tensors, the occupancy mask and the colour head's parameters. The encoder takes
// this and nothing of the trainer; the trainer describes its model so
// (trainer/rate/coded_model.h), and so could any other source of a TensoRF VM scene.
#ifndef ECRF_ENCODER_SCENE_DESCRIPTION_H_
#define ECRF_ENCODER_SCENE_DESCRIPTION_H_

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "format/mlp_coder.h"
#include "format/ndc_frame.h"
#include "format/scene_header.h"

namespace ecrf {
namespace encoder {

// The OCCU chunk's mask (SPEC.md 6.3): a 0/1 volume over its own box.
struct OccupancyDescription {
  std::array<float, 3> aabb_min{};
  std::array<float, 3> aabb_max{};
  std::array<int, 3> res{{2, 2, 2}};  // points along x, y, z (>= 2)
  std::vector<uint8_t> occupancy;     // res[2] x res[1] x res[0] bytes ([z][y][x], x fastest)
};

struct SceneDescription {
  // Geometry (object: the scene box; unbounded: the region of interest; forward-facing: the NDC
  // box), grid resolution, ranks (a mode may have rank 0), render parameters and head shape.
  // has_occupancy is the encoder's to set (EncodeOptions::include_occupancy and `mask`).
  SceneHeader header;
  NdcFrame ndc;  // forward-facing scenes only
  // tensors[g][t]: grid g (0 density, 1 appearance), planes t = 0..2 then lines t = 3..5,
  // channels-last: plane m [res[v]][res[u]][rank], line m [res[w]][rank] (format/vm_modes.h).
  std::array<std::array<std::vector<float>, 6>, 2> tensors;
  // The basis [feature_dim x total appearance rank], then the MLP in the MLPW order (SPEC.md 6.6).
  std::vector<float> head_params;
  HeadKind head = HeadKind::kPerSample;  // where the MLP runs (the MLPW head byte, SPEC.md 6.6)
  int mlp_hidden_layers = 2;             // 1 or 2 (the MLPW layers byte; 1 needs bitstream 1.8)
  std::optional<OccupancyDescription> mask;
};

}  // namespace encoder
}  // namespace ecrf

#endif  // ECRF_ENCODER_SCENE_DESCRIPTION_H_
