#include "trainer/train/eval_progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace ecrf {
namespace trainer {

std::vector<size_t> EvalViews(size_t n, int stride, int max_views) {
  std::vector<size_t> views;
  for (size_t v = 0; v < n; v += size_t(std::max(1, stride))) {
    if (max_views > 0 && views.size() >= size_t(max_views)) break;
    views.push_back(v);
  }
  return views;
}

EvalProgress::EvalProgress(std::string label, int total_views, double quiet_seconds)
    : label_(std::move(label)),
      total_(total_views),
      quiet_seconds_(quiet_seconds),
      terminal_(isatty(2) != 0),
      start_(Clock::now()),
      last_print_(start_) {}

EvalProgress::~EvalProgress() {
  if (printed_ && terminal_) std::fputc('\n', stderr);
}

std::string EvalProgress::Line(int done, double seconds, const std::string& extra) const {
  const double per_view = seconds / std::max(1, done);
  char text[256];
  std::snprintf(text, sizeof(text), "%s: view %d/%d, %.1f s/view, %.0f s left", label_.c_str(),
                done, total_, per_view, per_view * std::max(0, total_ - done));
  return extra.empty() ? std::string(text) : std::string(text) + ", " + extra;
}

void EvalProgress::ViewDone(const std::string& extra) {
  ++done_;
  const Clock::time_point now = Clock::now();
  const double seconds = std::chrono::duration<double>(now - start_).count();
  if (seconds < quiet_seconds_) return;
  const bool last = done_ >= total_;
  if (!terminal_ && !last && printed_ &&
      std::chrono::duration<double>(now - last_print_).count() < 10.0)
    return;
  const std::string line = Line(done_, seconds, extra);
  std::fprintf(stderr, terminal_ ? "\r%s\033[K" : "%s\n", line.c_str());
  std::fflush(stderr);
  printed_ = true;
  last_print_ = now;
}

}  // namespace trainer
}  // namespace ecrf
