// Figures printed by a benchmark and optionally written as a flat JSON object (--json FILE), and
// the command-line pieces the benchmarks share.
#ifndef ECRF_TOOLS_BENCH_BENCH_JSON_H_
#define ECRF_TOOLS_BENCH_BENCH_JSON_H_

#include <string>
#include <utility>
#include <vector>

#include "tools/cli.h"

namespace ecrf {
namespace tools {

class BenchReport {
 public:
  // Prints "name: value unit" and records it for JSON.
  void Add(const std::string& name, double value, const std::string& unit);
  // Records it for JSON only (a benchmark that prints its own table).
  void Record(const std::string& name, double value) { figures_.emplace_back(name, value); }
  // Writes {"name": value, ...} to path (nlohmann-json, atomically). Returns false on error,
  // after printing it.
  bool WriteJson(const std::string& path) const;

 private:
  std::vector<std::pair<std::string, double>> figures_;
};

// --threads LIST for the benchmarks that measure several thread counts one after the other:
// "1,2,0" (0 = all cores, as --threads elsewhere), checked while parsing.
CLI::Option* AddThreadListFlag(CLI::App* app, std::string* list);
// The counts of a list that AddThreadListFlag accepted, 0 replaced by AllCores().
std::vector<int> ThreadCounts(const std::string& list);

// Parses the command line of a benchmark whose only flag is --json FILE (into *json_path).
// Returns -1 to run, else the exit code (tools/cli.h's ParseCommandLine).
int ParseJsonOnlyCommandLine(const std::string& name, const std::string& description, int argc,
                             char** argv, std::string* json_path);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_BENCH_BENCH_JSON_H_
