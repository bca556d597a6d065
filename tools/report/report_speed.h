// The speed–error half of `ecrf report`: decode time and memory, then the render time per view
// and the PSNR of the decoded file for each speed knob of the renderer (SPEC.md 7.8), one knob
// at a time from the default settings.
#ifndef ECRF_TOOLS_REPORT_REPORT_SPEED_H_
#define ECRF_TOOLS_REPORT_REPORT_SPEED_H_

#include <nlohmann/json.hpp>
#include <string>

namespace ecrf {
namespace tools {

struct SpeedSweepOptions {
  double lambda = -1.0;  // the rate point to measure (< 0: the middle point of the sweep)
  int stride = 0;        // every stride-th test view (0: twice the sweep's test stride)
  int max_views = 0;     // at most this many views (0: no cap)
};

// Measures the point's scene.ecrf, stores the result as report["speed"] and rewrites the report
// in dir.
void RunSpeedSweep(const std::string& dir, const SpeedSweepOptions& options,
                   nlohmann::json* report);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_REPORT_REPORT_SPEED_H_
