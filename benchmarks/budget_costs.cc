// What a unit of charged work costs, class by class (#60: every charge at what it costs): each
// costly stream of conformance/costly_classes.h decoded at the default budgets of SPEC.md 8 and a
// 64x64 view of it rendered on one thread, with the units each charged. Built from format/ and
// decoder/ alone, so that scripts/budget-costs.sh can build it for every target of the
// conformance matrix (ARM under qemu included) and compare the classes' nanoseconds per unit.
//
//   budget_costs            # one line per class: name, decode units, seconds, render units,
//                           # seconds, outcome
#include <chrono>
#include <cstdio>
#include <vector>

#include "conformance/costly_classes.h"
#include "decoder/camera.h"
#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"

namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int main() {
  using namespace ecrf;
  std::printf("# class decode_units decode_s render_units render_s outcome\n");
  for (const costly::CostlyClass& c : costly::CostlyClasses()) {
    const std::vector<uint8_t> bytes = costly::BuildCostlyStream(c.scene);
    dec::SceneField field;
    dec::SceneInfo info;
    auto start = std::chrono::steady_clock::now();
    const Status decoded =
        dec::DecodeScene(bytes.data(), bytes.size(), dec::DecodeOptions(), &field, &info);
    const double decode_s = SecondsSince(start);
    double render_s = 0.0;
    dec::RenderStats stats;
    Status rendered = decoded;
    if (decoded.ok()) {
      dec::RenderOptions options;
      options.num_threads = 1;  // qemu-user runs threads one after another anyway
      dec::RayMarcher marcher;
      const dec::Camera camera = dec::OrbitCameraDegrees(64, 64, 0.0, 0.0, 3.f);
      std::vector<uint8_t> rgba(64 * 64 * 4);
      start = std::chrono::steady_clock::now();
      rendered = marcher.Init(&field, options);
      if (rendered.ok()) rendered = marcher.RenderImage(camera, rgba.data(), nullptr, &stats);
      render_s = SecondsSince(start);
    }
    const char* outcome = !decoded.ok()    ? "decode_refused"
                          : !rendered.ok() ? "render_refused"
                                           : "rendered";
    std::printf("%s %llu %.6f %llu %.6f %s\n", c.name,
                static_cast<unsigned long long>(info.decode_work), decode_s,
                static_cast<unsigned long long>(stats.work), render_s, outcome);
    std::fflush(stdout);
  }
  return 0;
}
