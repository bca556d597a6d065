#include "tools/bench/bench_json.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "tools/cli.h"
#include "trainer/data/file_io.h"

namespace ecrf {
namespace tools {

void BenchReport::Add(const std::string& name, double value, const std::string& unit) {
  std::printf("  %-44s %14.4g %s\n", name.c_str(), value, unit.c_str());
  std::fflush(stdout);
  figures_.emplace_back(name, value);
}

bool BenchReport::WriteJson(const std::string& path) const {
  // In the order printed; a non-finite figure (a zero-time division) is null.
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& [name, value] : figures_) {
    if (std::isfinite(value)) {
      j[name] = value;
    } else {
      j[name] = nullptr;
    }
  }
  try {
    trainer::WriteFileAtomically(path, j.dump(2) + "\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return false;
  }
  return true;
}

namespace {

// Throws std::invalid_argument (CLI11 puts the flag's name in front when it checks the value).
std::vector<int> ParseThreadList(const std::string& list) {
  std::vector<int> counts;
  size_t pos = 0;
  do {
    const size_t comma = std::min(list.find(',', pos), list.size());
    const std::string item = list.substr(pos, comma - pos);
    char* end = nullptr;
    const long v = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || v < 0 || v > 4096) {
      throw std::invalid_argument("'" + list +
                                  "' is not a comma-separated list of thread counts in [0, 4096]");
    }
    counts.push_back(int(v));
    pos = comma + 1;
  } while (pos <= list.size());
  return counts;
}

}  // namespace

CLI::Option* AddThreadListFlag(CLI::App* app, std::string* list) {
  const CLI::Validator check(
      [](std::string& text) {
        try {
          ParseThreadList(text);
          return std::string();
        } catch (const std::invalid_argument& e) {
          return std::string(e.what());
        }
      },
      "");
  return app
      ->add_option("--threads", *list,
                   "thread counts to measure, one after the other (0 = all cores: " +
                       std::to_string(AllCores()) + ")")
      ->type_name("LIST")
      ->check(check)
      ->capture_default_str();
}

std::vector<int> ThreadCounts(const std::string& list) {
  std::vector<int> counts = ParseThreadList(list);
  for (int& c : counts) c = c > 0 ? c : AllCores();
  return counts;
}

int ParseJsonOnlyCommandLine(const std::string& name, const std::string& description, int argc,
                             char** argv, std::string* json_path) {
  auto app = MakeCommand(name, description);
  app->add_option("--json", *json_path, "also write the figures as a flat JSON object")
      ->type_name("FILE");
  return ParseCommandLine(app.get(), argc, argv);
}

}  // namespace tools
}  // namespace ecrf
