// `ecrf bench coder`: speed of the range coder and the coefficient coder, and how the coefficient
// coder compresses compared with the order-0 entropy of the same int8 values and with zstd -19.
#include <zstd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "format/coefficients/coef_coder.h"
#include "format/entropy/range_coder.h"
#include "tools/bench/bench_json.h"
#include "tools/bench/benches.h"

namespace ecrf {
namespace tools {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kMinSeconds = 0.5;

// Runs `body` (which processes `items` items) until kMinSeconds have passed; returns M items/s.
template <typename Body>
double MeasureMillionsPerSecond(double items, Body body) {
  const Clock::time_point start = Clock::now();
  double seconds = 0;
  int runs = 0;
  do {
    body();
    ++runs;
    seconds = std::chrono::duration<double>(Clock::now() - start).count();
  } while (seconds < kMinSeconds);
  return items * runs / seconds / 1e6;
}

// Quantized Laplacian DCT coefficients of a 16x16x16 block: scale falls with the frequency sum,
// most high frequencies quantize to zero, values clip to int8 without -128.
std::vector<int32_t> LaplacianBlock(std::mt19937& rng, const BlockShape& shape, double dc_scale,
                                    double decay) {
  std::vector<int32_t> block(static_cast<size_t>(shape.Volume()));
  std::exponential_distribution<double> exponential(1.0);
  std::bernoulli_distribution coin(0.5);
  int raster = 0;
  for (int i = 0; i < shape.n0; ++i) {
    for (int j = 0; j < shape.n1; ++j) {
      for (int k = 0; k < shape.n2; ++k, ++raster) {
        const double scale = dc_scale * std::exp(-decay * (i + j + k));
        const double magnitude = std::min(127.0, std::floor(scale * exponential(rng) + 0.5));
        block[static_cast<size_t>(raster)] =
            static_cast<int32_t>(coin(rng) ? -magnitude : magnitude);
      }
    }
  }
  return block;
}

struct BlockSet {
  BlockShape shape;
  std::vector<std::vector<int32_t>> blocks;
  size_t Coefficients() const { return blocks.size() * static_cast<size_t>(shape.Volume()); }
};

BlockSet SparseBlocks(int count) {
  BlockSet set{BlockShape{16, 16, 16}, {}};
  std::mt19937 rng(1);
  std::bernoulli_distribution coded(0.3);
  for (int n = 0; n < count; ++n) {
    if (coded(rng)) {
      set.blocks.push_back(LaplacianBlock(rng, set.shape, 24.0, 0.35));
    } else {
      set.blocks.emplace_back(static_cast<size_t>(set.shape.Volume()), 0);
    }
  }
  return set;
}

BlockSet DenseBlocks(int count) {
  BlockSet set{BlockShape{16, 16, 16}, {}};
  std::mt19937 rng(2);
  for (int n = 0; n < count; ++n) set.blocks.push_back(LaplacianBlock(rng, set.shape, 12.0, 0.0));
  return set;
}

std::vector<uint8_t> EncodeBlocks(const BlockSet& set) {
  CoefContexts contexts;
  if (!contexts.Init(set.shape).ok()) return {};
  RangeEncoder encoder;
  for (const auto& block : set.blocks) EncodeCoefBlock(encoder, contexts, block.data());
  return encoder.Finish();
}

struct CoefFigures {
  double encode_mcoef_s = 0;
  double decode_mcoef_s = 0;
  double bits_per_coef = 0;
  double entropy_bits_per_coef = 0;
  double zstd19_bits_per_coef = 0;
  bool decoded_exactly = false;
};

CoefFigures MeasureCoefficients(const BlockSet& set) {
  CoefFigures figures;
  const double coefficients = static_cast<double>(set.Coefficients());
  const std::vector<uint8_t> stream = EncodeBlocks(set);
  figures.bits_per_coef = 8.0 * static_cast<double>(stream.size()) / coefficients;
  figures.encode_mcoef_s = MeasureMillionsPerSecond(coefficients, [&] { EncodeBlocks(set); });

  CoefContexts contexts;
  if (!contexts.Init(set.shape).ok()) return figures;
  std::vector<int32_t> out(static_cast<size_t>(set.shape.Volume()));
  bool exact = true;
  figures.decode_mcoef_s = MeasureMillionsPerSecond(coefficients, [&] {
    contexts.Reset();
    RangeDecoder decoder(stream.data(), stream.size());
    for (const auto& block : set.blocks) {
      if (!DecodeCoefBlock(decoder, contexts, 127, out.data()).ok()) exact = false;
      exact = exact && out == block;
    }
    exact = exact && decoder.Finish().ok();
  });
  figures.decoded_exactly = exact;

  std::vector<int8_t> int8_values;
  int8_values.reserve(set.Coefficients());
  for (const auto& block : set.blocks) {
    for (int32_t v : block) int8_values.push_back(static_cast<int8_t>(v));
  }
  std::vector<double> histogram(256, 0.0);
  for (int8_t v : int8_values) histogram[static_cast<uint8_t>(v)] += 1;
  double entropy = 0;
  for (double count : histogram) {
    if (count > 0) entropy -= count * std::log2(count / coefficients);
  }
  figures.entropy_bits_per_coef = entropy / coefficients;
  std::vector<uint8_t> zstd_out(ZSTD_compressBound(int8_values.size()));
  const size_t zstd_size =
      ZSTD_compress(zstd_out.data(), zstd_out.size(), int8_values.data(), int8_values.size(), 19);
  if (!ZSTD_isError(zstd_size)) {
    figures.zstd19_bits_per_coef = 8.0 * static_cast<double>(zstd_size) / coefficients;
  }
  return figures;
}

// Symbols of a 16-ary alphabet with a geometric-like skew (about 2.3 bits each).
std::vector<uint8_t> SkewedSymbols(size_t count) {
  std::mt19937 rng(3);
  std::geometric_distribution<int> geometric(0.35);
  std::vector<uint8_t> symbols(count);
  for (uint8_t& s : symbols) s = static_cast<uint8_t>(std::min(geometric(rng), 15));
  return symbols;
}

std::vector<uint8_t> EncodeSymbols(const std::vector<uint8_t>& symbols) {
  uint16_t cdf[kMaxSymbols + 1];
  InitUniformCdf(cdf, kMaxSymbols);
  RangeEncoder encoder;
  for (uint8_t s : symbols) encoder.EncodeSymbol(s, cdf, kMaxSymbols);
  return encoder.Finish();
}

}  // namespace

int RunCoderBench(int argc, char** argv) {
  std::string json;
  const int rc = ParseJsonOnlyCommandLine(
      "bench coder",
      "speed of the range coder and the coefficient coder (one thread), and how the coefficient "
      "coder compresses "
      "compared with the order-0 entropy of the same int8 values and with zstd -19",
      argc, argv, &json);
  if (rc >= 0) return rc;
  BenchReport report;
  const std::vector<uint8_t> symbols = SkewedSymbols(1 << 20);
  const std::vector<uint8_t> symbol_stream = EncodeSymbols(symbols);
  const double symbol_count = static_cast<double>(symbols.size());
  size_t symbol_mismatches = 0;
  std::printf("range coder, adaptive 16-ary alphabet, skewed symbols (one thread)\n");
  report.Add("symbol_bits", 8.0 * static_cast<double>(symbol_stream.size()) / symbol_count,
             "bits/symbol");
  report.Add("symbol_encode_msym_per_s",
             MeasureMillionsPerSecond(symbol_count, [&] { EncodeSymbols(symbols); }), "M/s");
  report.Add(
      "symbol_decode_msym_per_s",
      MeasureMillionsPerSecond(symbol_count,
                               [&] {
                                 uint16_t cdf[kMaxSymbols + 1];
                                 InitUniformCdf(cdf, kMaxSymbols);
                                 RangeDecoder decoder(symbol_stream.data(), symbol_stream.size());
                                 for (uint8_t s : symbols) {
                                   symbol_mismatches += decoder.DecodeSymbol(cdf, kMaxSymbols) != s;
                                 }
                               }),
      "M/s");

  bool exact = symbol_mismatches == 0;
  const std::pair<const char*, BlockSet> sets[] = {{"sparse", SparseBlocks(400)},
                                                   {"dense", DenseBlocks(40)}};
  for (const auto& named : sets) {
    const std::string name = named.first;
    std::printf("coefficient coder, %s 16x16x16 int8 blocks%s\n", named.first,
                name == "sparse" ? " (70% all zero, Laplacian decaying with frequency)"
                                 : " (Laplacian, no decay)");
    const CoefFigures f = MeasureCoefficients(named.second);
    exact = exact && f.decoded_exactly;
    report.Add(name + "_encode_mcoef_per_s", f.encode_mcoef_s, "M/s");
    report.Add(name + "_decode_mcoef_per_s", f.decode_mcoef_s, "M/s");
    report.Add(name + "_bits_per_coef", f.bits_per_coef, "bits");
    report.Add(name + "_order0_entropy_bits_per_coef", f.entropy_bits_per_coef, "bits");
    report.Add(name + "_zstd19_bits_per_coef", f.zstd19_bits_per_coef, "bits");
  }
  if (!exact) std::fprintf(stderr, "ecrf bench coder: DECODE MISMATCH\n");

  if (!json.empty() && !report.WriteJson(json)) {
    std::fprintf(stderr, "ecrf bench coder: cannot write %s\n", json.c_str());
    return 1;
  }
  return exact ? 0 : 1;
}

}  // namespace tools
}  // namespace ecrf
