// A progress line for evaluations long enough to wonder about (full-resolution captures can take
// minutes per view): nothing for the first seconds, then the views done, the time per view and
// an estimate of what is left, on stderr (rewritten in place on a terminal, at most one line
// every 10 s in a log).
#ifndef ECRF_TRAINER_TRAIN_EVAL_PROGRESS_H_
#define ECRF_TRAINER_TRAIN_EVAL_PROGRESS_H_

#include <chrono>
#include <cstddef>
#include <string>
#include <vector>

#include "trainer/data/seconds_since.h"

namespace ecrf {
namespace trainer {

// The views an evaluation of every stride-th of n views, at most max_views (0 = all), renders,
// in order: one rule for scoring the float model, the decoded file, and for choosing the held-out
// cameras that are aligned before scoring.
std::vector<size_t> EvalViews(size_t n, int stride, int max_views);
inline int EvalViewCount(size_t n, int stride, int max_views) {
  return int(EvalViews(n, stride, max_views).size());
}

class EvalProgress {
 public:
  EvalProgress(std::string label, int total_views, double quiet_seconds = 2.0);
  ~EvalProgress();
  EvalProgress(const EvalProgress&) = delete;
  EvalProgress& operator=(const EvalProgress&) = delete;

  // After each view; extra is appended to the line (e.g. samples per ray).
  void ViewDone(const std::string& extra = std::string());
  // The line ViewDone prints for `done` views after `seconds` (for tests).
  std::string Line(int done, double seconds, const std::string& extra) const;

 private:
  using Clock = std::chrono::steady_clock;
  std::string label_;
  int total_;
  int done_ = 0;
  double quiet_seconds_;
  bool terminal_;
  bool printed_ = false;
  Clock::time_point start_;
  Clock::time_point last_print_;
};

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_EVAL_PROGRESS_H_
