// A per-phase model of how a step's phases scale with threads, fitted to times measured at a few
// thread counts: Amdahl's law (a serial fraction), capped by the phase's independent tasks and
// floored by the bytes it streams over the memory bandwidth. `ecrf bench train` prints it.
#ifndef ECRF_TOOLS_BENCH_SCALING_MODEL_H_
#define ECRF_TOOLS_BENCH_SCALING_MODEL_H_

#include <string>
#include <vector>

namespace ecrf {
namespace tools {

// The serial fraction s of t(N) = t(1) (s + (1 - s) / N), least squares over the measured counts
// above 1, clamped to [0, 1]. seconds[i] was measured on threads[i]; threads must hold 1.
// Returns -1 when there is no count above 1 to fit.
double FitSerialFraction(const std::vector<int>& threads, const std::vector<double>& seconds);

struct PhaseModel {
  double t1 = 0.0;             // seconds on one thread
  double serial = 0.0;         // fitted serial fraction
  double bytes = 0.0;          // bytes streamed per step (0: not a streaming phase)
  std::vector<int> max_tasks;  // per predicted count: the phase's independent tasks (0: many)
};

struct Prediction {
  double seconds = 0.0;
  // What sets the time: "serial" (the serial part is at least the parallel part), "tasks" (fewer
  // tasks than threads), "memory" (the bytes over the bandwidth), else "parallel".
  std::string bound;
};

// The phase's time on `threads` threads (max_tasks: that count's task limit, 0 = none) with
// `bandwidth` bytes per second of memory bandwidth available to all threads together.
Prediction PredictPhase(const PhaseModel& phase, int threads, int max_tasks, double bandwidth);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_BENCH_SCALING_MODEL_H_
