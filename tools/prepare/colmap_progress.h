// Progress inside COLMAP's long phases, read from the lines it prints: `ecrf prepare` showed one
// line per phase, and exhaustive matching of 50 phone photos ran 24 minutes without a word.
#ifndef ECRF_TOOLS_PREPARE_COLMAP_PROGRESS_H_
#define ECRF_TOOLS_PREPARE_COLMAP_PROGRESS_H_

#include <chrono>
#include <cstdio>
#include <string>

namespace ecrf {
namespace tools {

// Units of a phase done, of how many.
struct ColmapStep {
  long done = 0;
  long total = 0;
};

// One line of COLMAP 3.x output: "Processed file [i/N]" (feature extraction), "Matching block
// [i/N, j/M]" and "Matching block [i/N]" (exhaustive matching), "Matching image [i/N]"
// (sequential matching), "Registering image #id (k)" (mapping: k images of `frames` registered).
// True, with *step set, when the line is one of them.
bool ParseColmapProgress(const std::string& line, int frames, ColmapStep* step);

// Shows a phase's progress and what is left: "prepare: COLMAP exhaustive matching: 40%, 3m10s
// left". On a terminal one line is rewritten at most every second; in a log a line is written at
// most every 30 seconds. `out` is where (stderr; tests give a file).
class ColmapProgress {
 public:
  ColmapProgress(std::string phase, int frames, std::FILE* out = stderr);
  void operator()(const std::string& line);
  // Ends a rewritten line.
  void Finish();

 private:
  std::string phase_;
  int frames_;
  std::FILE* out_;
  bool terminal_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_PREPARE_COLMAP_PROGRESS_H_
