// What a unit of charged work costs, class by class (#60: every charge at what it costs): each
// costly stream of conformance/costly_classes.h decoded at the default budgets of SPEC.md 8 and a
// 64x64 view of it rendered on one thread, with the units each charged. Built from format/ and
// decoder/ alone, so that scripts/budget-costs.sh can build it for every target of the
// conformance matrix (ARM under qemu included) and compare the classes' nanoseconds per unit.
//
//   budget_costs            # one line per class: name, decode units, seconds, render units,
//                           # seconds, outcome
#include <cstdio>

#include "conformance/costly_classes.h"

int main() {
  std::printf("# class decode_units decode_s render_units render_s outcome\n");
  for (const ecrf::costly::CostlyClass& c : ecrf::costly::CostlyClasses()) {
    // One thread: qemu-user runs threads one after another anyway.
    const ecrf::costly::CostlyMeasurement m = ecrf::costly::MeasureCostlyClass(c, 1);
    std::printf("%s %llu %.6f %llu %.6f %s\n", c.name,
                static_cast<unsigned long long>(m.info.decode_work), m.decode_s,
                static_cast<unsigned long long>(m.stats.work), m.render_s, m.outcome());
    std::fflush(stdout);
  }
  return 0;
}
