// `ecrf bench idct`: integer inverse DCT throughput on 16x16x16 blocks (dense, typical sparse,
// all-zero) and 1x8x8 line blocks, one thread, against the float64 reference transform.
#include <chrono>
#include <cstdio>
#include <random>
#include <vector>

#include "format/coefficients/block_shape.h"
#include "format/coefficients/coef_coder.h"
#include "format/coefficients/float_dct.h"
#include "format/coefficients/int_idct.h"
#include "format/entropy/range_coder.h"
#include "tools/bench/bench_json.h"
#include "tools/bench/benches.h"
#include "trainer/data/seconds_since.h"

namespace ecrf {
namespace tools {
namespace {

// Blocks whose coefficients are Laplacian with a scale that decays with frequency, quantized;
// `zero_fraction` of the blocks are all zero (typical of a rate-constrained model).
std::vector<int32_t> MakeBlocks(const int dims[3], int count, double scale, double zero_fraction,
                                uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int v = BlockVolume(dims);
  std::vector<int32_t> blocks(size_t(v) * count, 0);
  for (int b = 0; b < count; ++b) {
    if (u(rng) < zero_fraction) continue;
    for (int i0 = 0; i0 < dims[0]; ++i0)
      for (int i1 = 0; i1 < dims[1]; ++i1)
        for (int i2 = 0; i2 < dims[2]; ++i2) {
          const double s = scale / (1.0 + (i0 + i1 + i2) * (i0 + i1 + i2) * 0.5);
          std::exponential_distribution<double> e(1.0 / s);
          double m = std::floor(e(rng));
          if (m > 127) m = 127;
          blocks[size_t(b) * v + (i0 * dims[1] + i1) * dims[2] + i2] =
              int32_t(u(rng) < 0.5 ? -m : m);
        }
  }
  return blocks;
}

double CoefficientsPerSecond(const std::vector<int32_t>& blocks, const int dims[3]) {
  const int v = BlockVolume(dims);
  const int count = int(blocks.size() / v);
  std::vector<int32_t> out(v);
  long coefficients = 0;
  volatile int32_t sink = 0;
  const auto start = std::chrono::steady_clock::now();
  double elapsed = 0;
  do {
    for (int b = 0; b < count; ++b) {
      InverseDctInt(&blocks[size_t(b) * v], dims, 8, out.data());
      sink = sink + out[b % v];
    }
    coefficients += long(count) * v;
    elapsed = trainer::SecondsSince(start);
  } while (elapsed < 0.5);
  return coefficients / elapsed;
}

double FloatCoefficientsPerSecond(const std::vector<int32_t>& blocks, const int dims[3]) {
  const int v = BlockVolume(dims);
  const int count = int(blocks.size() / v);
  std::vector<double> work(v);
  long coefficients = 0;
  const auto start = std::chrono::steady_clock::now();
  double elapsed = 0;
  do {
    for (int b = 0; b < count; ++b) {
      for (int i = 0; i < v; ++i) work[i] = blocks[size_t(b) * v + i];
      InverseDct(work.data(), dims);
    }
    coefficients += long(count) * v;
    elapsed = trainer::SecondsSince(start);
  } while (elapsed < 0.5);
  return coefficients / elapsed;
}

// Entropy decoding followed by the integer IDCT: what a decoder spends per coefficient of a grid.
double DecodePlusIdctPerSecond(const std::vector<int32_t>& blocks, const int dims[3]) {
  const BlockShape shape{dims[0], dims[1], dims[2]};
  const int v = BlockVolume(dims);
  const int count = int(blocks.size() / v);
  CoefContexts enc_ctx;
  if (!enc_ctx.Init(shape).ok()) return 0;
  RangeEncoder enc;
  for (int b = 0; b < count; ++b) EncodeCoefBlock(enc, enc_ctx, &blocks[size_t(b) * v]);
  const std::vector<uint8_t> stream = enc.Finish();
  std::vector<int32_t> coeffs(v), out(v);
  long coefficients = 0;
  volatile int32_t sink = 0;
  const auto start = std::chrono::steady_clock::now();
  double elapsed = 0;
  do {
    CoefContexts ctx;
    if (!ctx.Init(shape).ok()) return 0;
    RangeDecoder dec(stream.data(), stream.size());
    for (int b = 0; b < count; ++b) {
      int eob = 0;
      if (!DecodeCoefBlock(dec, ctx, 127, coeffs.data(), &eob).ok()) return 0;
      InverseDctInt(coeffs.data(), dims, 8, out.data());
      sink = sink + out[b % v];
    }
    coefficients += long(count) * v;
    elapsed = trainer::SecondsSince(start);
  } while (elapsed < 0.5);
  return coefficients / elapsed;
}

}  // namespace

int RunIdctBench(int argc, char** argv) {
  std::string json;
  const int rc =
      ParseJsonOnlyCommandLine("bench idct",
                               "integer inverse DCT throughput on 16x16x16 blocks (dense, typical "
                               "sparse, all-zero) and 1x8x8 line blocks, "
                               "one thread, alone and after the coefficient decoder, against the "
                               "float64 reference transform",
                               argc, argv, &json);
  if (rc >= 0) return rc;
  BenchReport report;
  std::printf("integer inverse DCT, one thread (coefficients per second, input included)\n");
  const int cube[3] = {16, 16, 16};
  const int line[3] = {1, 8, 8};
  const auto dense = MakeBlocks(cube, 64, 40.0, 0.0, 1);
  const auto sparse = MakeBlocks(cube, 256, 3.0, 0.7, 2);
  const auto zeros = MakeBlocks(cube, 256, 3.0, 1.0, 3);
  const auto lines = MakeBlocks(line, 4096, 4.0, 0.3, 4);
  report.Add("idct_16x16x16_dense_mcoef_per_s", CoefficientsPerSecond(dense, cube) / 1e6, "M/s");
  report.Add("idct_16x16x16_sparse_mcoef_per_s", CoefficientsPerSecond(sparse, cube) / 1e6, "M/s");
  report.Add("idct_16x16x16_zero_mcoef_per_s", CoefficientsPerSecond(zeros, cube) / 1e6, "M/s");
  report.Add("idct_1x8x8_lines_mcoef_per_s", CoefficientsPerSecond(lines, line) / 1e6, "M/s");
  report.Add("decode_plus_idct_16x16x16_sparse_mcoef_per_s",
             DecodePlusIdctPerSecond(sparse, cube) / 1e6, "M/s");
  report.Add("decode_plus_idct_16x16x16_dense_mcoef_per_s",
             DecodePlusIdctPerSecond(dense, cube) / 1e6, "M/s");
  report.Add("decode_plus_idct_1x8x8_lines_mcoef_per_s", DecodePlusIdctPerSecond(lines, line) / 1e6,
             "M/s");
  report.Add("float64_idct_16x16x16_dense_mcoef_per_s",
             FloatCoefficientsPerSecond(dense, cube) / 1e6, "M/s");
  if (!json.empty() && !report.WriteJson(json)) {
    std::fprintf(stderr, "ecrf bench idct: cannot write %s\n", json.c_str());
    return 1;
  }
  return 0;
}

}  // namespace tools
}  // namespace ecrf
