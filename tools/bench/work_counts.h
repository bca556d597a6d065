// Work counts of the trainer's compute phases, so that benchmarks can state a measured time as a
// share of this CPU's measured peak (cpu_peak.h, scaling_model.h's triad bandwidth).
#ifndef ECRF_TOOLS_BENCH_WORK_COUNTS_H_
#define ECRF_TOOLS_BENCH_WORK_COUNTS_H_

#include "trainer/model/appearance_head.h"

namespace ecrf {
namespace tools {

// Floating-point operations of one forward and one backward of the appearance head over n rows
// (an FMA counts 2): the basis, the hidden layers the head has, the output layer.
struct MlpFlops {
  double forward = 0.0, backward = 0.0;
};
MlpFlops HeadFlops(const trainer::AppearanceHeadConfig& cfg, const trainer::AppearanceHead& head,
                   long n);

// The gradient scatter's arithmetic and traffic for the given samples of a VM grid pair: per
// sample, mode and component, the plane's 4 bilinear corners and the line's 2 take one FMA each,
// into gradients read and written (8 bytes an entry). *_rank_sum: the components summed over the
// three modes. The traffic counts every entry as a memory access, so the GB/s it gives is what
// the scatter would need if nothing stayed in the cache: a ceiling to hold the triad bandwidth
// against, not a measurement of it.
struct ScatterWork {
  double flops = 0.0, bytes = 0.0;
};
ScatterWork ScatterCounts(long density_samples, int density_rank_sum, long appearance_samples,
                          int appearance_rank_sum);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_BENCH_WORK_COUNTS_H_
