// One training run as `ecrf train` does it: train, encode RUN/scene.ecrf, decode that file with
// the embeddable decoder, score it, and write RUN/metrics.json. Shared by `ecrf train` and the
// rate-distortion sweep of `ecrf report`.
#ifndef ECRF_TOOLS_TRAIN_RUN_H_
#define ECRF_TOOLS_TRAIN_RUN_H_

#include <nlohmann/json.hpp>

#include "trainer/train_options.h"

namespace ecrf {
namespace tools {

// Options for a command line: the preset (named anywhere on the line; "tiny" when --scene builtin
// has no --preset), then the rate point (--rate, also named anywhere), then every training flag
// of argv that ParseTrainFlag knows, so that flags override the preset and the point whatever
// their order. Flags it does not know are left for the caller: their
// indices go to *rest. rate_point_by_default (`ecrf train`): without --lambda-e, --rate or
// --target-size the run trains at the "medium" rate point.
trainer::TrainOptions TrainOptionsFromArgs(int argc, char** argv, std::vector<int>* rest,
                                           bool rate_point_by_default = false);

// The training flags' usage lines (data, schedule, ECRF objective, bookkeeping).
extern const char kTrainFlagsUsage[];

// Checks that options name data and an output directory it can create, creates it (with
// parents), then trains, encodes, decodes and evaluates. Prints the summary lines to stdout.
// Returns what it writes to RUN/metrics.json. Throws std::exception with a message on failure.
nlohmann::json TrainEncodeEvaluate(const trainer::TrainOptions& options);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_TRAIN_RUN_H_
