#include "tools/bench/cpu_peak.h"

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

// The widest FMA of this build: a vector type and the few operations RunChains needs.
#if defined(__AVX512F__)
struct Simd {
  using V = __m512;
  static constexpr int kLanes = 16;
  static V Set(float x) { return _mm512_set1_ps(x); }
  static V Fma(V a, V b, V c) { return _mm512_fmadd_ps(a, b, c); }
  static void Store(float* p, V v) { _mm512_storeu_ps(p, v); }
};
#elif defined(__AVX2__) && defined(__FMA__)
struct Simd {
  using V = __m256;
  static constexpr int kLanes = 8;
  static V Set(float x) { return _mm256_set1_ps(x); }
  static V Fma(V a, V b, V c) { return _mm256_fmadd_ps(a, b, c); }
  static void Store(float* p, V v) { _mm256_storeu_ps(p, v); }
};
#else
struct Simd {
  using V = float;
  static constexpr int kLanes = 1;
  static V Set(float x) { return x; }
  static V Fma(V a, V b, V c) { return std::fma(a, b, c); }
  static void Store(float* p, V v) { *p = v; }
};
#endif
constexpr int kLanes = Simd::kLanes;

float RunChains(long rounds) {
  Simd::V acc[kChains];
  for (int i = 0; i < kChains; ++i) acc[i] = Simd::Set(0.001f * i);
  const Simd::V a = Simd::Set(0.5f), b = Simd::Set(0.25f);
  for (long r = 0; r < rounds; ++r) {
#pragma GCC unroll 12
    for (int i = 0; i < kChains; ++i) acc[i] = Simd::Fma(a, acc[i], b);
  }
  float total = 0.f;
  for (int i = 0; i < kChains; ++i) {
    float lanes[kLanes];
    Simd::Store(lanes, acc[i]);
    for (float v : lanes) total += v;
  }
  return total;
}

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
