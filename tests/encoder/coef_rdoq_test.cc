#include "encoder/coef_rdoq.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <random>
#include <vector>

#include "encoder/coef_quantizer.h"
#include "format/coefficients/coef_coder.h"
#include "format/entropy/range_coder.h"

namespace ecrf {
namespace trainer {
namespace {

// A plane-like tensor's coefficients: 8 x 8 x 8 blocks, 3 x 2 x 2 of them, Laplacian magnitudes
// decaying with frequency as a smooth feature grid's do.
struct Tensor {
  encoder::GridBlockLayout layout;
  std::vector<float> coeffs;
};

Tensor MakeTensor(uint32_t seed) {
  Tensor t;
  const int extent[3] = {24, 16, 16};
  const long stride[3] = {1, 24 * 16, 24};
  const int block[3] = {8, 8, 8};
  t.layout = encoder::MakeBlockLayout(extent, stride, block);
  t.coeffs.resize(t.layout.num_coeffs());
  std::mt19937 rng(seed);
  std::exponential_distribution<double> magnitude(1.0);
  std::bernoulli_distribution negative(0.5);
  for (size_t i = 0; i < t.coeffs.size(); ++i) {
    const int r = int(i % 512), f = r / 64 + (r / 8) % 8 + r % 8;
    const double scale = 6.0 * std::exp(-0.35 * f);
    t.coeffs[i] = float((negative(rng) ? -1 : 1) * scale * magnitude(rng));
  }
  return t;
}

// The real coder's bytes for the levels (neighbour contexts, as the encoder's newest set).
std::vector<uint8_t> Code(const std::vector<int32_t>& levels,
                          const encoder::GridBlockLayout& layout) {
  CoefContexts contexts;
  EXPECT_TRUE(contexts
                  .Init(BlockShape{layout.block[0], layout.block[1], layout.block[2]},
                        CoefContextSet::kNeighbour, layout.blocks, size_t(-1))
                  .ok());
  RangeEncoder enc;
  for (int b = 0; b < layout.num_blocks(); ++b) {
    EncodeCoefBlock(enc, contexts, &levels[size_t(b) * layout.block_volume()]);
  }
  return enc.Finish();
}

double Distortion(const Tensor& t, const std::vector<int32_t>& levels, double step) {
  double d = 0.0;
  for (size_t i = 0; i < levels.size(); ++i) {
    const double e = double(t.coeffs[i]) / step - levels[i];
    d += e * e;
  }
  return d;
}

std::vector<int32_t> Levels(const Tensor& t, double step, double lambda, int32_t max_abs = 127) {
  encoder::RdoqOptions o;
  o.lambda = lambda;
  o.max_abs = max_abs;
  std::vector<int32_t> levels(t.coeffs.size());
  encoder::RdoqLevels(t.coeffs.data(), t.layout, step, o, levels.data());
  return levels;
}

TEST(CoefRdoq, LambdaZeroIsTheRoundingQuantizer) {
  const Tensor t = MakeTensor(1);
  const double step = 0.05;  // levels past 127: the clip is exercised too
  const std::vector<int32_t> levels = Levels(t, step, 0.0);
  int clipped = 0;
  for (size_t i = 0; i < levels.size(); ++i) {
    const double plain = encoder::QuantizeLevel(double(t.coeffs[i]), step, 0.5);
    clipped += std::fabs(plain) > 127;
    ASSERT_EQ(levels[i], int32_t(std::max(-127.0, std::min(127.0, plain)))) << i;
  }
  EXPECT_GT(clipped, 0);
  std::vector<int32_t> again(levels.size());
  EXPECT_EQ(
      encoder::RdoqLevels(t.coeffs.data(), t.layout, step, encoder::RdoqOptions(), again.data()),
      size_t(clipped));
}

TEST(CoefRdoq, LevelsOnlyShrinkTowardZero) {
  const Tensor t = MakeTensor(2);
  for (double lambda : {0.05, 0.3, 2.0}) {
    const std::vector<int32_t> plain = Levels(t, 0.5, 0.0), rd = Levels(t, 0.5, lambda);
    size_t changed = 0, dropped_blocks = 0;
    for (size_t i = 0; i < rd.size(); ++i) {
      ASSERT_LE(std::abs(rd[i]), std::abs(plain[i])) << i;
      ASSERT_TRUE(rd[i] == 0 || (rd[i] < 0) == (plain[i] < 0)) << i;
      // At most one level down, or 2 -> 0, unless the whole block was dropped.
      const size_t volume = size_t(t.layout.block_volume()), first = i / volume * volume;
      const bool block_dropped =
          std::all_of(rd.begin() + long(first), rd.begin() + long(first + volume),
                      [](int32_t v) { return v == 0; });
      dropped_blocks += block_dropped && i == first;
      if (!block_dropped) {
        ASSERT_GE(std::abs(rd[i]), std::abs(plain[i]) - (std::abs(plain[i]) <= 2 ? 2 : 1)) << i;
      }
      changed += rd[i] != plain[i];
    }
    EXPECT_GT(changed, 0u) << lambda;
    if (lambda == 2.0) EXPECT_GT(dropped_blocks, 0u);
  }
}

// The point of RDOQ: a lower distortion + lambda * bits than rounding, with the bits the real
// coder spends (not the estimate it decided with), over a range of lambdas and steps.
TEST(CoefRdoq, LowersTheCodedRateDistortionCost) {
  for (uint32_t seed : {3u, 4u}) {
    const Tensor t = MakeTensor(seed);
    for (double step : {0.25, 1.0}) {
      const std::vector<int32_t> plain = Levels(t, step, 0.0);
      const double plain_bits = 8.0 * double(Code(plain, t.layout).size());
      const double plain_d = Distortion(t, plain, step);
      double previous_bits = plain_bits;
      for (double lambda : {0.05, 0.12, 0.5, 2.0}) {
        const std::vector<int32_t> rd = Levels(t, step, lambda);
        const double bits = 8.0 * double(Code(rd, t.layout).size());
        const double d = Distortion(t, rd, step);
        EXPECT_LT(d + lambda * bits, plain_d + lambda * plain_bits)
            << "seed " << seed << " step " << step << " lambda " << lambda;
        EXPECT_LT(bits, plain_bits);
        EXPECT_LE(bits, previous_bits * 1.01) << "a larger lambda should not cost more bits";
        previous_bits = bits;
      }
    }
  }
}

TEST(CoefRdoq, CodedLevelsDecodeExactly) {
  const Tensor t = MakeTensor(5);
  const std::vector<int32_t> rd = Levels(t, 0.5, 0.3);
  const std::vector<uint8_t> bytes = Code(rd, t.layout);
  const encoder::GridBlockLayout& layout = t.layout;
  CoefContexts contexts;
  ASSERT_TRUE(contexts
                  .Init(BlockShape{layout.block[0], layout.block[1], layout.block[2]},
                        CoefContextSet::kNeighbour, layout.blocks, size_t(-1))
                  .ok());
  RangeDecoder dec(bytes.data(), bytes.size());
  std::vector<int32_t> decoded(rd.size());
  for (int b = 0; b < layout.num_blocks(); ++b) {
    ASSERT_TRUE(
        DecodeCoefBlock(dec, contexts, 127, &decoded[size_t(b) * layout.block_volume()]).ok());
  }
  EXPECT_TRUE(dec.Finish().ok());
  EXPECT_EQ(decoded, rd);
}

TEST(CoefRdoq, DeterministicAndUnclippedWhenAsked) {
  const Tensor t = MakeTensor(6);
  EXPECT_EQ(Levels(t, 0.05, 0.2, INT32_MAX), Levels(t, 0.05, 0.2, INT32_MAX));
  const std::vector<int32_t> wide = Levels(t, 0.05, 0.2, INT32_MAX);
  int32_t largest = 0;
  for (int32_t v : wide) largest = std::max(largest, std::abs(v));
  EXPECT_GT(largest, 127);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
