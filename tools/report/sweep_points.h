// The points of `ecrf report sweep`: the rate points, file sizes and lambda_e values that --rates,
// --targets and --lambdas name, each point's own `ecrf train` arguments and run name, and the
// check that a finished run in REPORT/runs/ was trained as the sweep would train it, so that the
// sweep (or its --plan) reuses it.
#ifndef ECRF_TOOLS_REPORT_SWEEP_POINTS_H_
#define ECRF_TOOLS_REPORT_SWEEP_POINTS_H_

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "trainer/train/train_options.h"

namespace ecrf {
namespace tools {

// One run of the sweep: a named rate point (--rate R), a file size (--target-size SIZE) or a
// lambda_e on the sweep's base (--lambda-e X, with --quant-step-scale S for "X@S"), resolved like
// the same `ecrf train` command line.
struct SweepPoint {
  std::string rate;    // "" for a lambda or size point
  std::string target;  // "" for a lambda or rate point
  double lambda = 0.0;
  float step_scale = 0.0f;  // 0: the base's
};

// The points of --rates R,..., --targets S,... and --lambdas L[@S],..., in that order (an empty
// text names none; a lambda given twice is one point). Throws for an unknown rate point, a size
// that is not a plain word, or a lambda or step scale that does not parse.
std::vector<SweepPoint> ParseSweepPoints(const std::string& rates, const std::string& targets,
                                         const std::string& lambdas);

// The point's own `ecrf train` arguments: --rate R, --target-size S or --lambda-e X (with
// --quant-step-scale S for "X@S").
std::vector<std::string> PointArgs(const SweepPoint& p);

// The point's run directory under REPORT/runs/: rate_R, target_S or the lambda's LambdaText.
std::string PointName(const SweepPoint& p, const trainer::TrainOptions& resolved);

// Whether two data paths name the same data (relative paths as seen from the current directory).
bool SameData(const std::string& a, const std::string& b);

// Throws std::runtime_error, naming the settings that differ and what to do, unless the finished
// run whose metrics.json (at `path`) is `metrics` was trained with the options `o`.
void CheckReusable(const nlohmann::json& metrics, const trainer::TrainOptions& o,
                   const std::string& path);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_REPORT_SWEEP_POINTS_H_
