// Figures printed by a benchmark and optionally written as a flat JSON object (--json FILE).
#ifndef ECRF_TOOLS_BENCH_JSON_H_
#define ECRF_TOOLS_BENCH_JSON_H_

#include <string>
#include <utility>
#include <vector>

namespace ecrf {
namespace tools {

class BenchReport {
 public:
  // Prints "name: value unit" and records it for JSON.
  void Add(const std::string& name, double value, const std::string& unit);
  // Writes {"name": value, ...} to path via a temp file and rename. Returns false on error.
  bool WriteJson(const std::string& path) const;

 private:
  std::vector<std::pair<std::string, double>> figures_;
};

// Finds "--json FILE" in argv; empty when absent.
std::string JsonPathFromArgs(int argc, char** argv);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_BENCH_JSON_H_
