#include "tools/bench/scaling_model.h"

#include <algorithm>

namespace ecrf {
namespace tools {

double FitSerialFraction(const std::vector<int>& threads, const std::vector<double>& seconds) {
  double t1 = -1.0;
  for (size_t i = 0; i < threads.size() && i < seconds.size(); ++i)
    if (threads[i] == 1) t1 = seconds[i];
  if (!(t1 > 0.0)) return -1.0;
  // t(N) / t1 - 1/N = s (1 - 1/N): a line through the origin in x = 1 - 1/N.
  double sxy = 0.0, sxx = 0.0;
  for (size_t i = 0; i < threads.size() && i < seconds.size(); ++i) {
    if (threads[i] <= 1) continue;
    const double n = threads[i];
    const double x = 1.0 - 1.0 / n, y = seconds[i] / t1 - 1.0 / n;
    sxy += x * y;
    sxx += x * x;
  }
  if (sxx == 0.0) return -1.0;
  return std::min(1.0, std::max(0.0, sxy / sxx));
}

Prediction PredictPhase(const PhaseModel& phase, int threads, int max_tasks, double bandwidth) {
  const int usable = max_tasks > 0 ? std::min(threads, max_tasks) : threads;
  const double s = std::max(0.0, phase.serial);
  const double serial = phase.t1 * s, parallel = phase.t1 * (1.0 - s) / std::max(1, usable);
  Prediction p;
  p.seconds = serial + parallel;
  p.bound = serial >= parallel ? "serial" : (usable < threads ? "tasks" : "parallel");
  if (phase.bytes > 0.0 && bandwidth > 0.0 && phase.bytes / bandwidth > p.seconds) {
    p.seconds = phase.bytes / bandwidth;
    p.bound = "memory";
  }
  return p;
}

}  // namespace tools
}  // namespace ecrf
