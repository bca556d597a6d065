// One training run as `ecrf train` does it: train, encode RUN/scene.ecrf, decode that file with
// the embeddable decoder, score it, and write RUN/metrics.json. Shared by `ecrf train` and the
// rate-distortion sweep of `ecrf report`.
#ifndef ECRF_TOOLS_TRAIN_RUN_H_
#define ECRF_TOOLS_TRAIN_RUN_H_

#include <nlohmann/json.hpp>

#include "trainer/train/train_options.h"

namespace ecrf {
namespace tools {

// Checks that options name data and an output directory it can create, creates it (with
// parents), refuses a --resume whose settings differ from the checkpoint's (unless
// accept_config_change), writes RUN/config.json, then trains, encodes, decodes and scores the
// decoded file (and the float model with score_float). Prints the summary lines to stdout.
// Returns what it writes to RUN/metrics.json. Throws std::exception with a message on failure.
nlohmann::json TrainEncodeEvaluate(const trainer::TrainOptions& options);

// Whether RUN/checkpoint.ckpt exists and was written with the settings of `options`: a run
// stopped (Ctrl-C, SIGTERM, a kill) that --resume can continue.
bool CanResume(const trainer::TrainOptions& options);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_TRAIN_RUN_H_
