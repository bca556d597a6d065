// `ecrf bench budgets`: the costliest small streams of each class (conformance/costly_streams.h)
// against the default budgets of SPEC.md 8: their size, what decoding them costs (seconds, the
// memory the decoder's budget granted) and what a 64x64 view costs (seconds), with the outcome.
// The budgets' goal: no stream of at most 64 KB takes more than 2 s to decode or 1 s to render
// at 64x64 on 2 cores, while trained scenes decode and render unchanged.
#include <cstdio>
#include <string>

#include "conformance/costly_classes.h"
#include "tools/bench/bench_json.h"
#include "tools/bench/benches.h"

namespace ecrf {
namespace tools {

int RunBudgetBench(int argc, char** argv) {
  std::string json;
  if (const int rc = ParseJsonOnlyCommandLine(
          "bench budgets",
          "the costliest small streams of each class against the default decode and render "
          "budgets (SPEC.md 8): bytes, decode seconds and memory, 64x64 render seconds on 2 "
          "threads",
          argc, argv, &json);
      rc >= 0) {
    return rc;
  }
  BenchReport report;
  std::printf("%-26s %8s %9s %10s %10s %9s %10s  %s\n", "stream", "bytes", "decode s", "units/B",
              "memory MiB", "render s", "work/px", "outcome");
  for (const costly::CostlyClass& c : costly::CostlyClasses()) {
    const costly::CostlyMeasurement m = costly::MeasureCostlyClass(c, 2);
    const double memory_mib = static_cast<double>(m.info.memory_bytes) / (1 << 20);
    const double units_per_byte =
        static_cast<double>(m.info.decode_work) / static_cast<double>(m.bytes);
    const double work_per_pixel = static_cast<double>(m.stats.work) / (64.0 * 64.0);
    std::printf("%-26s %8zu %9.3f %10.0f %10.1f %9.3f %10.0f  %s (%s)\n", c.name, m.bytes,
                m.decode_s, units_per_byte, memory_mib, m.render_s, work_per_pixel, m.outcome(),
                c.what);
    const std::string key = std::string("budgets.") + c.name;
    if (!json.empty()) {
      report.Add(key + ".bytes", static_cast<double>(m.bytes), "B");
      report.Add(key + ".decode_s", m.decode_s, "s");
      report.Add(key + ".memory_mib", memory_mib, "MiB");
      report.Add(key + ".render_64x64_s", m.render_s, "s");
      report.Add(key + ".refused", m.decoded.ok() && m.rendered.ok() ? 0.0 : 1.0, "");
    }
  }
  if (!json.empty() && !report.WriteJson(json)) {
    std::fprintf(stderr, "ecrf bench budgets: cannot write %s\n", json.c_str());
    return 1;
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
