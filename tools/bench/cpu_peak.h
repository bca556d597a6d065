// The single-precision FMA peak of this CPU, measured: the yardstick for the trainer's GEMMs.
#ifndef ECRF_TOOLS_BENCH_CPU_PEAK_H_
#define ECRF_TOOLS_BENCH_CPU_PEAK_H_

namespace ecrf {
namespace tools {

// GFLOP/s of `threads` OpenMP threads each running independent chains of the widest FMA this
// build targets (AVX-512, AVX2+FMA, else scalar fmaf) for about `seconds`; an FMA counts 2 FLOP.
double MeasureFmaPeakGflops(int threads, double seconds = 0.2);

// "avx512", "avx2+fma" or "scalar": what MeasureFmaPeakGflops runs.
const char* FmaPeakIsa();

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_BENCH_CPU_PEAK_H_
