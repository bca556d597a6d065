// The work budget of a render (SPEC.md section 8): what a view may cost, counted in multiply-adds
// of the reference process, so that a stream cannot make a renderer spend minutes on a pixel.
//
// The sample budget bounds samples per ray; what a sample costs depends on the stream: its density
// ranks, and for a coloured sample the appearance ranks and the MLP (F, H, P, Ff, Fv). The widest
// head the format allows (F 256, H 1024, P 3072) costs 10.6 M multiply-adds per coloured sample,
// 4000 times a trained scene's. The renderer therefore charges every ray for what it does
// (marched positions, density evaluations, colour evaluations) against a budget of
// `work_budget` multiply-adds per pixel on average over the view, and refuses:
//   - when preparing (Init): a scene one colour sample of which costs more than a pixel's budget;
//   - while rendering: a view that spends its budget (pixels x work_budget); the render stops
//     within one sample of the limit and returns kErrLimit, naming the count and the remedy.
// Work is counted per sample, so a view's count does not depend on the thread count or the
// tiling. Threads take the budget from a shared pool in shares of 2^22, so a view whose work comes
// within threads x 2^22 of its budget may be refused with more threads and accepted with fewer;
// below that margin every thread count accepts it, above its budget every one refuses it.
// The unit is one multiply-add of the MLP; the other steps count what they take in time against
// it (measured with `ecrf bench budgets` on this project's 2-core x86-64 machine: a marched
// position ~100 ns, a density evaluation ~200 ns plus ~3 ns per rank in a large grid, an MLP
// multiply-add ~0.16 ns).
#ifndef ECRF_DECODER_RENDER_WORK_H_
#define ECRF_DECODER_RENDER_WORK_H_

#include <cstdint>

#include "decoder/field.h"
#include "ecrf/decoder.h"

namespace ecrf {
namespace dec {

// Default RenderOptions::work_budget, per pixel on average over a view. Trained Synthetic-NeRF
// scenes spend at most ~1/10 of it on their most expensive views (docs/benchmarks-and-fuzzing.md).
inline constexpr uint64_t kDefaultWorkBudget = ECRF_DEFAULT_WORK_BUDGET;

// A positional-encoding argument of magnitude above 8192 (or not finite) leaves the vectorised
// sin/cos for the library's (decoder/mlp.h): ~10-13 ns a pair here, about 80 units where the
// coloured sample's cost counts 16. The renderer charges each such pair this much more, after the
// batch of at most RayMarcher's batch capacity rows that computed it (the argument is only known
// then), so a view stops within one batch of its budget.
inline constexpr uint64_t kWideSinCosWork = 64;

struct SampleCosts {
  uint64_t position = 0;  // a marched sample position: box, mask and contraction tests
  uint64_t density = 0;   // its density: grid location, 7 taps per density rank, softplus, exp
  // Its colour: per-sample head, the appearance taps, the basis, positional encoding and MLP;
  // deferred head, the appearance taps and their weighted sum.
  uint64_t color = 0;
  uint64_t ray_head = 0;  // deferred head: the basis, encoding and MLP once per coloured ray
  // The most one ray of n samples can cost: every sample evaluated and coloured.
  uint64_t WorstRay(int n) const {
    return static_cast<uint64_t>(n) * (position + density + color) + ray_head;
  }
};

// Costs of the samples of a head with these widths over grids of these total ranks (the weights
// of the work budget). Overflow-free for every scene the format allows: each cost is below 2^26.
inline SampleCosts HeadSampleCosts(HeadKind kind, const MlpConfig& m, int density_rank,
                                   int appearance_rank) {
  constexpr uint64_t kRank = 16;  // the 7 taps of one rank of one mode (gathers)
  const uint64_t F = static_cast<uint64_t>(m.feature_dim), H = static_cast<uint64_t>(m.hidden);
  const uint64_t P = static_cast<uint64_t>(appearance_rank);
  const uint64_t in = static_cast<uint64_t>(m.input_dim());
  SampleCosts c;
  c.position = 768;
  c.density = 1024 + kRank * static_cast<uint64_t>(density_rank);
  // Sines and cosines of the positional encoding count 8 each.
  const uint64_t pe = 8 * 2 *
                      (F * static_cast<uint64_t>(m.feature_pe_freqs) +
                       3 * static_cast<uint64_t>(m.viewdir_pe_freqs));
  const uint64_t second_layer = m.hidden_layers == 2 ? H * H : 0;
  const uint64_t head = F * P + pe + in * H + second_layer + 3 * H + 256;
  if (kind == HeadKind::kDeferred) {
    c.color = kRank * P + P;
    c.ray_head = head;
  } else {
    c.color = kRank * P + head;
  }
  return c;
}

// The costs of a decoded scene's samples.
inline SampleCosts SceneSampleCosts(const SceneField& s) {
  return HeadSampleCosts(s.head, s.mlp.config(), s.density.total_rank(), s.appearance.total_rank());
}

// The work per pixel of a view from its mean counts per ray (marched positions, evaluated
// samples, coloured samples, the share of rays with a coloured sample).
inline double WorkPerPixel(const SampleCosts& c, double positions, double samples, double coloured,
                           double coloured_rays) {
  return positions * static_cast<double>(c.position) + samples * static_cast<double>(c.density) +
         coloured * static_cast<double>(c.color) + coloured_rays * static_cast<double>(c.ray_head);
}

// Render budgets of device classes (ecrf train --device-class), in the work units of this file
// per pixel: the multiply-adds a class performs per second, over the frame rate and pixels asked
// of it. The units weigh the density steps by their time on a CPU (above), so on a GPU these are
// estimates. phone: about 1 TFLOP/s (5e11 multiply-adds/s), 30 frames/s at 800x800; the same as
// this project's 2-core Zen 4 rendering a 400x400 frame in 0.1 s (chair with the deferred head:
// 66 k units per pixel in 0.25 s a frame, 42 G units/s; docs/results.md). laptop: an integrated
// GPU of about 3 TFLOP/s at 30 frames/s, 800x800. desktop: about 10 TFLOP/s at 60 frames/s,
// 800x800.
struct DeviceClass {
  const char* name;
  uint64_t work_per_pixel;
};
inline constexpr DeviceClass kDeviceClasses[] = {
    {"desktop", 130000},
    {"laptop", 78000},
    {"phone", 26000},
};

}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_DECODER_RENDER_WORK_H_
