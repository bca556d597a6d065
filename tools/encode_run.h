// How a trained run becomes its .ecrf file, shared by `ecrf train` (at the end of training) and
// `ecrf encode RUN` (later, from the checkpoint and its stored configuration), so that both write
// the same bytes for the same settings.
#ifndef ECRF_TOOLS_ENCODE_RUN_H_
#define ECRF_TOOLS_ENCODE_RUN_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "encoder/encode_rate_control.h"
#include "encoder/scene_encoder.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/train/rate_state.h"
#include "trainer/train/train_options.h"

namespace ecrf {
namespace tools {

// What the metadata chunk says of the data: the procedural scene's name, the dataset folder's
// name, or with meta_data_path the path as given.
std::string MetaDataSource(const trainer::TrainOptions& config);

// The encoder settings of a run: its block shapes and frozen steps, coefficient depth, MLP levels
// and rounding offset, and the metadata chunk (data, preset, iterations, final lambda_e, alpha).
encoder::EncodeOptions TrainedRunEncodeOptions(const trainer::TrainOptions& config,
                                               const trainer::RateState& rate, int iterations,
                                               float final_lambda_e);

struct EncodedRun {
  std::vector<uint8_t> bytes;
  encoder::EncodeReport report;
  double step_scale = 1.0;  // encode-time factor on every step (1 without a target)
  int encodes = 1;
};

// Encodes once, or with target_bytes > 0 searches the step scale for the largest file of at
// most that size (trainer::EncodeToTargetSize).
EncodedRun EncodeRun(const trainer::TensorfModel& model, const encoder::EncodeOptions& options,
                     size_t target_bytes);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_ENCODE_RUN_H_
