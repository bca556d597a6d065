#include "tools/cpu_peak.h"

#include <omp.h>

#include <cmath>

#if defined(__AVX512F__) || (defined(__AVX2__) && defined(__FMA__))
#include <immintrin.h>
#endif

namespace ecrf {
namespace tools {
namespace {

// Twelve independent accumulators cover the FMA latency x throughput of current x86 cores, so
// the loop is bound by FMA issue alone. Multiplier 0.5 and addend 0.25 keep every value finite
// and normal (a chain converges to 0.5): denormals or infinities would slow some CPUs down.
constexpr int kChains = 12;

#if defined(__AVX512F__)
constexpr int kLanes = 16;
float RunChains(long rounds) {
  __m512 acc[kChains];
  for (int i = 0; i < kChains; ++i) acc[i] = _mm512_set1_ps(0.001f * i);
  const __m512 a = _mm512_set1_ps(0.5f), b = _mm512_set1_ps(0.25f);
  for (long r = 0; r < rounds; ++r) {
#pragma GCC unroll 12
    for (int i = 0; i < kChains; ++i) acc[i] = _mm512_fmadd_ps(a, acc[i], b);
  }
  __m512 s = acc[0];
  for (int i = 1; i < kChains; ++i) s = _mm512_add_ps(s, acc[i]);
  float lanes[16];
  _mm512_storeu_ps(lanes, s);
  float total = 0.f;
  for (float v : lanes) total += v;
  return total;
}
#elif defined(__AVX2__) && defined(__FMA__)
constexpr int kLanes = 8;
float RunChains(long rounds) {
  __m256 acc[kChains];
  for (int i = 0; i < kChains; ++i) acc[i] = _mm256_set1_ps(0.001f * i);
  const __m256 a = _mm256_set1_ps(0.5f), b = _mm256_set1_ps(0.25f);
  for (long r = 0; r < rounds; ++r) {
#pragma GCC unroll 12
    for (int i = 0; i < kChains; ++i) acc[i] = _mm256_fmadd_ps(a, acc[i], b);
  }
  __m256 s = acc[0];
  for (int i = 1; i < kChains; ++i) s = _mm256_add_ps(s, acc[i]);
  float lanes[8];
  _mm256_storeu_ps(lanes, s);
  float total = 0.f;
  for (float v : lanes) total += v;
  return total;
}
#else
constexpr int kLanes = 1;
float RunChains(long rounds) {
  float acc[kChains];
  for (int i = 0; i < kChains; ++i) acc[i] = 0.001f * i;
  for (long r = 0; r < rounds; ++r) {
    for (int i = 0; i < kChains; ++i) acc[i] = std::fma(0.5f, acc[i], 0.25f);
  }
  float total = 0.f;
  for (float v : acc) total += v;
  return total;
}
#endif

}  // namespace

const char* FmaPeakIsa() {
#if defined(__AVX512F__)
  return "avx512";
#elif defined(__AVX2__) && defined(__FMA__)
  return "avx2+fma";
#else
  return "scalar";
#endif
}

double MeasureFmaPeakGflops(int threads, double seconds) {
  if (threads < 1) threads = 1;
  // Calibrate the round count on one thread, then time all threads together.
  long rounds = 1 << 16;
  volatile float sink = 0.f;
  for (;;) {
    const double t0 = omp_get_wtime();
    sink = sink + RunChains(rounds);
    const double dt = omp_get_wtime() - t0;
    if (dt > seconds / 4 || rounds > (1L << 40)) {
      rounds = static_cast<long>(rounds * (seconds / (dt > 0 ? dt : 1e-9)));
      break;
    }
    rounds *= 4;
  }
  if (rounds < 1) rounds = 1;
  float total = 0.f;
  const double t0 = omp_get_wtime();
#pragma omp parallel num_threads(threads) reduction(+ : total)
  total += RunChains(rounds);
  const double dt = omp_get_wtime() - t0;
  sink = sink + total;
  return 2.0 * kChains * kLanes * static_cast<double>(rounds) * threads / dt * 1e-9;
}

}  // namespace tools
}  // namespace ecrf
