// Wall-clock seconds since a steady-clock time point: the one timer the trainer, the CLI's
// progress lines and the benchmarks report with.
#ifndef ECRF_TRAINER_DATA_SECONDS_SINCE_H_
#define ECRF_TRAINER_DATA_SECONDS_SINCE_H_

#include <chrono>

namespace ecrf {
namespace trainer {

inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_DATA_SECONDS_SINCE_H_
