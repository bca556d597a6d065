// `ecrf bench render`: the renderer's speed on a synthetic scene, without a trained model. The
// blob scene has a trained scene's shape (ranks, MLP, a solid object whose surface spans a few
// samples, an alpha mask), so samples per second and milliseconds per view compare across
// machines and builds; a trained file's speed against its error is `ecrf report render`.
#ifndef ECRF_TOOLS_BENCH_RENDER_BENCH_H_
#define ECRF_TOOLS_BENCH_RENDER_BENCH_H_

#include <cstdint>

#include "decoder/field.h"
#include "decoder/ray_marcher.h"
#include "format/status.h"

namespace ecrf {
namespace tools {

// A res^3 scene over [-1.5,1.5]^3: density ranks 16, appearance ranks 48 (P = 144), feature 27,
// hidden 128; random small grids (seeded) plus a separable smooth box of dense density
// off-centre (an opaque object whose surface spans a few samples); random MLP (PyTorch-like
// init). with_mask: alpha mask at res^3 from the density (TensoRF's updateAlphaMask:
// alpha >= 1e-4 after a 3x3x3 max-pool).
Status MakeBlobScene(int res, dec::GridStorage storage, bool with_mask, uint32_t seed,
                     dec::SceneField* scene);

struct RenderBenchResult {
  int threads = 0;
  int views = 0;
  double ms_per_view = 0.0;
  double msamples_per_s = 0.0;        // density-evaluated samples
  double mcolor_samples_per_s = 0.0;  // MLP samples
  uint64_t samples_per_view = 0;
  uint64_t color_samples_per_view = 0;
  uint64_t image_hash = 0;  // FNV-1a of the last view's RGBA bytes: equal hashes, equal pixels
};

// Renders `views` orbit views of width x height (after one warm-up view) and times them.
Status BenchmarkRender(const dec::SceneField& scene, int width, int height, int threads, int views,
                       const dec::RenderOptions& base_options, RenderBenchResult* result);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_BENCH_RENDER_BENCH_H_
