#include "tools/prepare/colmap_progress.h"

#include <unistd.h>

#include <cstring>

namespace ecrf {
namespace tools {

bool ParseColmapProgress(const std::string& line, int frames, ColmapStep* step) {
  long i = 0, n = 0, j = 0, m = 0;
  const char* text = line.c_str();
  while (*text == ' ') ++text;
  if (std::sscanf(text, "Matching block [%ld/%ld, %ld/%ld]", &i, &n, &j, &m) == 4 && n > 0 &&
      m > 0) {
    *step = {(i - 1) * m + j, n * m};
    return true;
  }
  if ((std::sscanf(text, "Processed file [%ld/%ld]", &i, &n) == 2 ||
       std::sscanf(text, "Matching block [%ld/%ld]", &i, &n) == 2 ||
       std::sscanf(text, "Matching image [%ld/%ld]", &i, &n) == 2) &&
      n > 0) {
    *step = {i, n};
    return true;
  }
  if (std::sscanf(text, "Registering image #%ld (%ld)", &i, &j) == 2 && frames > 0) {
    *step = {j, frames};
    return true;
  }
  return false;
}

ColmapProgress::ColmapProgress(std::string phase, int frames, std::FILE* out)
    : phase_(std::move(phase)),
      frames_(frames),
      out_(out),
      terminal_(isatty(fileno(out)) != 0),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

void ColmapProgress::operator()(const std::string& line) {
  ColmapStep step;
  if (!ParseColmapProgress(line, frames_, &step) || step.done <= 0 || step.total <= 0) return;
  const auto now = std::chrono::steady_clock::now();
  const double since = std::chrono::duration<double>(now - last_).count();
  if (since < (terminal_ ? 1.0 : 30.0) && step.done < step.total) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double left =
      step.done >= step.total ? 0.0 : elapsed * double(step.total - step.done) / double(step.done);
  const int minutes = int(left) / 60, seconds = int(left) % 60;
  std::fprintf(out_, "%sprepare: %s: %ld/%ld (%d%%), %dm%02ds left%s", terminal_ ? "\r" : "",
               phase_.c_str(), step.done, step.total, int(100 * step.done / step.total), minutes,
               seconds, terminal_ ? "   " : "\n");
  std::fflush(out_);
  shown_ = true;
}

void ColmapProgress::Finish() {
  if (terminal_ && shown_) std::fprintf(out_, "\n");
  shown_ = false;
}

}  // namespace tools
}  // namespace ecrf
