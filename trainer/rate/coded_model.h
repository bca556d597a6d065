// The trainer's model as the encoder codes it. The encoder takes a format-level scene description
// (encoder/scene_description.h) and nothing of the trainer; DescribeModel makes one of a
// TensorfModel, and the overloads below are the encoder's entry points for a model. The rate
// objective trains through the same coded tensors, read in place from the model's grids
// (RateTensorLayout / RateTensorData / RateTensorGrad), so that the trained rate is the rate of
// the file.
#ifndef ECRF_TRAINER_RATE_CODED_MODEL_H_
#define ECRF_TRAINER_RATE_CODED_MODEL_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "encoder/coded_tensors.h"
#include "encoder/encode_rate_control.h"
#include "encoder/grid_dct.h"
#include "encoder/scene_description.h"
#include "encoder/scene_encoder.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/model/vm_grid.h"

namespace ecrf {
namespace trainer {

// The model as the stream sees it: HEAD (an unbounded scene's box is its region of interest, the
// grids spanning the contracted cube), the grids' tensors, the head's parameters and the alpha
// mask, copied.
encoder::SceneDescription DescribeModel(const TensorfModel& model);

// Tensor t (0..5: planes 0..2, then lines 0..2) of a grid: its block layout, and its values and
// gradients inside the grid's params() and grads().
encoder::GridBlockLayout RateTensorLayout(const VmGrid& grid, int t,
                                          const encoder::RateConfig& config);
const float* RateTensorData(const VmGrid& grid, int t);
float* RateTensorGrad(VmGrid& grid, int t);

// The encoder's functions (encoder/scene_encoder.h, encoder/encode_rate_control.h,
// encoder/coded_tensors.h) on DescribeModel(model).
std::vector<uint8_t> EncodeScene(const TensorfModel& model, const encoder::EncodeOptions& options,
                                 encoder::EncodeReport* report = nullptr);
encoder::TargetSizeResult EncodeToTargetSize(const TensorfModel& model,
                                             const encoder::EncodeOptions& options,
                                             size_t target_bytes);
std::vector<float> ChooseQuantSteps(const TensorfModel& model, const encoder::RateConfig& config,
                                    int coef_bits);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_RATE_CODED_MODEL_H_
