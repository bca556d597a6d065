// The classes of costly streams the budgets of SPEC.md 8 are measured against, one stream each
// (conformance/costly_streams.h builds them): `ecrf bench budgets` times them on this machine,
// benchmarks/budget_costs.cc (scripts/budget-costs.sh) per unit of charged work on each build,
// ARM under qemu included.
#ifndef ECRF_CONFORMANCE_COSTLY_CLASSES_H_
#define ECRF_CONFORMANCE_COSTLY_CLASSES_H_

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "conformance/costly_streams.h"
#include "decoder/camera.h"
#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"

namespace ecrf {
namespace costly {

struct CostlyClass {
  const char* name;  // a short key (JSON, tables)
  const char* what;  // what makes it costly
  CostlyScene scene;
};

inline std::vector<CostlyClass> CostlyClasses() {
  std::vector<CostlyClass> v;
  auto add = [&v](const char* name, const char* what, auto configure) {
    CostlyClass c{name, what, {}};
    configure(c.scene);
    v.push_back(c);
  };
  add("widest_head", "F 256, H 1024, P 3072, 16 frequencies, every sample coloured",
      [](CostlyScene& s) { s = WidestHead(); });
  add("wide_head_many_samples", "H 1024 (1.2 M per sample), 16384 samples, all coloured",
      [](CostlyScene& s) {
        s.appearance_rank = 48;
        s.feature_dim = 27;
        s.hidden = 1024;
        s.pe_freqs = 2;
      });
  add("small_head_many_samples", "H 64, 16384 samples, all coloured", [](CostlyScene& s) {
    s.appearance_rank = 8;
    s.feature_dim = 8;
    s.hidden = 64;
    s.pe_freqs = 2;
  });
  add("dense_density", "density ranks 3 x 1024, 16384 samples, none coloured", [](CostlyScene& s) {
    s.density_rank = 1024;
    s.weight_threshold = 1.f;
  });
  add("big_grid_density", "256^3 grid, rank 1, 16384 samples, none coloured", [](CostlyScene& s) {
    s.res = 256;
    s.weight_threshold = 1.f;
  });
  // The same charge per tap on planes past the caches (#60: taps in large grids miss them).
  add("huge_grid_density", "2048^3 grid, rank 1, 16384 samples, none coloured", [](CostlyScene& s) {
    s.res = 2048;
    s.weight_threshold = 1.f;
  });
  add("huge_grid_density_rank16", "1024^3 grid, rank 16, 16384 samples, none coloured",
      [](CostlyScene& s) {
        s.res = 1024;
        s.density_rank = 16;
        s.weight_threshold = 1.f;
      });
  add("unbounded_empty_mask", "unbounded, empty 64^3 mask: 16384 positions per ray",
      [](CostlyScene& s) {
        s.unbounded = true;
        s.occupancy = 2;
        s.occupancy_res = 64;
      });
  add("occupancy_empty_4096", "OCCU 4096 x 4096 x 112, no row flagged, 13 KB of meta",
      [](CostlyScene& s) {
        s.occupancy = 2;
        s.occupancy_res = 4096;
        s.occupancy_depth = 112;
        s.padding = 13000;  // the budget covers the mask's 29.4 M units
      });
  add("occupancy_empty_rows_512", "OCCU 512^3, every row flagged, no voxel set",
      [](CostlyScene& s) { s = EmptyFlaggedRows(512); });
  add("occupancy_empty_rows_1024", "OCCU 1024^3, every row flagged, no voxel set",
      [](CostlyScene& s) { s = EmptyFlaggedRows(1024); });
  add("neighbour_contexts_2048", "2048^2 planes of rank 1 in 16^3 blocks, neighbour contexts",
      [](CostlyScene& s) { s = NeighbourContexts2048(); });
  add("full_length_blocks", "512^2 planes, rank 16, 16^3 blocks coded to their last position",
      [](CostlyScene& s) { s = FullLengthBlocks(16); });
  add("full_length_small_blocks", "512^2 planes, rank 16, 4^3 blocks coded to their last position",
      [](CostlyScene& s) { s = FullLengthBlocks(4); });
  return v;
}

// What one class cost: its stream decoded at the default budgets of SPEC.md 8, then (if it
// decoded) a 64x64 view rendered on `threads` threads, each timed.
struct CostlyMeasurement {
  size_t bytes = 0;
  Status decoded, rendered;  // rendered: the decode's status when it failed
  dec::SceneInfo info;
  dec::RenderStats stats;
  double decode_s = 0.0, render_s = 0.0;
  const char* outcome() const {
    return !decoded.ok() ? "decode refused" : !rendered.ok() ? "render refused" : "rendered";
  }
};

inline CostlyMeasurement MeasureCostlyClass(const CostlyClass& c, int threads) {
  auto seconds_since = [](std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  CostlyMeasurement m;
  const std::vector<uint8_t> bytes = BuildCostlyStream(c.scene);
  m.bytes = bytes.size();
  dec::SceneField field;
  auto start = std::chrono::steady_clock::now();
  m.decoded = dec::DecodeScene(bytes.data(), bytes.size(), dec::DecodeOptions(), &field, &m.info);
  m.decode_s = seconds_since(start);
  m.rendered = m.decoded;
  if (!m.decoded.ok()) return m;
  dec::RenderOptions options;
  options.num_threads = threads;
  dec::RayMarcher marcher;
  const dec::Camera camera = dec::OrbitCameraDegrees(64, 64, 0.0, 0.0, 3.f);
  std::vector<uint8_t> rgba(64 * 64 * 4);
  start = std::chrono::steady_clock::now();
  m.rendered = marcher.Init(&field, options);
  if (m.rendered.ok()) m.rendered = marcher.RenderImage(camera, rgba.data(), nullptr, &m.stats);
  m.render_s = seconds_since(start);
  return m;
}

}  // namespace costly
}  // namespace ecrf

#endif  // ECRF_CONFORMANCE_COSTLY_CLASSES_H_
