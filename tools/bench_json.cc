#include "tools/bench_json.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace ecrf {
namespace tools {

void BenchReport::Add(const std::string& name, double value, const std::string& unit) {
  std::printf("  %-44s %14.4g %s\n", name.c_str(), value, unit.c_str());
  std::fflush(stdout);
  figures_.emplace_back(name, value);
}

bool BenchReport::WriteJson(const std::string& path) const {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) return false;
    out << "{\n";
    for (size_t i = 0; i < figures_.size(); ++i) {
      char value[64];
      if (std::isfinite(figures_[i].second)) {
        std::snprintf(value, sizeof(value), "%.9g", figures_[i].second);
      } else {
        std::snprintf(value, sizeof(value), "null");
      }
      out << "  \"" << figures_[i].first << "\": " << value << (i + 1 < figures_.size() ? ",\n" : "\n");
    }
    out << "}\n";
    if (!out.good()) return false;
  }
  return std::rename(tmp.c_str(), path.c_str()) == 0;
}

std::string JsonPathFromArgs(int argc, char** argv) {
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) return argv[i + 1];
  }
  return std::string();
}

}  // namespace tools
}  // namespace ecrf
