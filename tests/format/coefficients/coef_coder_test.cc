#include "format/coefficients/coef_coder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "tests/common/coef_test_blocks.h"

namespace ecrf {
namespace {

using testing_blocks::AllValidShapes;
using testing_blocks::ExpectedEob;
using testing_blocks::Fnv1a;
using testing_blocks::SplitMix;

int FrequencySum(const BlockShape& shape, int raster) {
  return raster % shape.n2 + (raster / shape.n2) % shape.n1 + raster / (shape.n2 * shape.n1);
}

// Sparse block whose magnitudes decay with frequency (integer-only, deterministic).
std::vector<int32_t> SparseBlock(SplitMix& rng, const BlockShape& shape, int32_t max_abs) {
  std::vector<int32_t> block(static_cast<size_t>(shape.Volume()), 0);
  for (int r = 0; r < shape.Volume(); ++r) {
    const int f = FrequencySum(shape, r);
    if (rng.Below(100) >= static_cast<uint32_t>(90 / (1 + f))) continue;
    const uint32_t scale = 1 + static_cast<uint32_t>(max_abs) / (4u << std::min(f, 20));
    int32_t magnitude = static_cast<int32_t>(1 + rng.Below(scale) * rng.Below(scale) / scale);
    if (rng.Below(50) == 0)
      magnitude = static_cast<int32_t>(1 + rng.Below(static_cast<uint32_t>(max_abs)));
    block[static_cast<size_t>(r)] = rng.Below(2) ? -magnitude : magnitude;
  }
  return block;
}

struct CodedBlocks {
  std::vector<std::vector<int32_t>> blocks;
  std::vector<uint8_t> bytes;
};

CodedBlocks Encode(const BlockShape& shape, std::vector<std::vector<int32_t>> blocks,
                   CoefContextSet set = CoefContextSet::kWide) {
  CoefContexts contexts;
  EXPECT_TRUE(contexts.Init(shape, set).ok());
  RangeEncoder encoder;
  for (const auto& block : blocks) EncodeCoefBlock(encoder, contexts, block.data());
  return {std::move(blocks), encoder.Finish()};
}

void ExpectDecodes(const BlockShape& shape, const CodedBlocks& coded, int32_t max_abs,
                   CoefContextSet set = CoefContextSet::kWide) {
  CoefContexts contexts;
  ASSERT_TRUE(contexts.Init(shape, set).ok());
  RangeDecoder decoder(coded.bytes.data(), coded.bytes.size());
  std::vector<int32_t> out(static_cast<size_t>(shape.Volume()), 12345);
  for (size_t b = 0; b < coded.blocks.size(); ++b) {
    int eob = -1;
    const Status status = DecodeCoefBlock(decoder, contexts, max_abs, out.data(), &eob);
    ASSERT_TRUE(status.ok()) << status.message() << " block " << b;
    ASSERT_EQ(out, coded.blocks[b]) << "block " << b;
    ASSERT_EQ(eob, ExpectedEob(shape, coded.blocks[b])) << "block " << b;
  }
  EXPECT_TRUE(decoder.Finish().ok());
}

TEST(CoefScanTest, FourByFourOrderIsByFrequencySumThenRaster) {
  const std::vector<uint16_t> expected = {0, 1, 4, 2, 5, 8, 3, 6, 9, 12, 7, 10, 13, 11, 14, 15};
  EXPECT_EQ(ComputeScanOrder(BlockShape{1, 4, 4}), expected);
  EXPECT_EQ(ComputeScanOrder(BlockShape{4, 1, 4}), expected);
}

TEST(CoefScanTest, EveryShapeScanIsAFrequencySortedPermutation) {
  for (const BlockShape& shape : AllValidShapes()) {
    const std::vector<uint16_t> scan = ComputeScanOrder(shape);
    ASSERT_EQ(scan.size(), static_cast<size_t>(shape.Volume()));
    std::vector<bool> seen(scan.size(), false);
    for (size_t s = 0; s < scan.size(); ++s) {
      ASSERT_FALSE(seen[scan[s]]);
      seen[scan[s]] = true;
      if (s > 0) {
        const int f0 = FrequencySum(shape, scan[s - 1]), f1 = FrequencySum(shape, scan[s]);
        ASSERT_TRUE(f0 < f1 || (f0 == f1 && scan[s - 1] < scan[s]));
      }
    }
  }
}

TEST(CoefScanTest, ShapeValidation) {
  EXPECT_EQ(AllValidShapes().size(), 206u);  // 216 combinations minus the volumes above 4096
  CoefContexts contexts;
  for (const BlockShape& bad : {BlockShape{3, 1, 1}, BlockShape{64, 1, 1}, BlockShape{0, 4, 4},
                                BlockShape{32, 32, 8}, BlockShape{1, -2, 1}}) {
    EXPECT_EQ(contexts.Init(bad).code(), kErrInvalidArgument);
  }
  EXPECT_TRUE(contexts.Init(BlockShape{32, 32, 4}).ok());
  EXPECT_TRUE(contexts.Init(BlockShape{1, 1, 1}).ok());
}

TEST(CoefCoderTest, RoundTripEveryShapeWithBothContextSets) {
  SplitMix rng(42);
  for (const BlockShape& shape : AllValidShapes()) {
    for (const CoefContextSet set : {CoefContextSet::kNarrow, CoefContextSet::kWide}) {
      SCOPED_TRACE(testing::Message() << shape.n0 << "x" << shape.n1 << "x" << shape.n2
                                      << (set == CoefContextSet::kWide ? " wide" : " narrow"));
      const size_t volume = static_cast<size_t>(shape.Volume());
      std::vector<std::vector<int32_t>> blocks;
      blocks.emplace_back(volume, 0);  // all zero
      blocks.emplace_back(volume, 0);
      blocks.back()[0] = -7;  // DC only
      blocks.emplace_back(volume, 0);
      blocks.back()[volume - 1] = 1;  // highest frequency only (eob = volume)
      blocks.emplace_back(volume, 0);
      blocks.back()[volume - 1] = -127;
      for (int n = 0; n < 4; ++n) blocks.push_back(SparseBlock(rng, shape, 127));
      blocks.emplace_back(volume, 0);
      for (size_t r = 0; r < volume; ++r)
        blocks.back()[r] = static_cast<int32_t>(rng.Below(255)) - 127;
      blocks.emplace_back(volume, 0);
      ExpectDecodes(shape, Encode(shape, std::move(blocks), set), 127, set);
    }
  }
}

// Blocks like those of trained feature grids: each has its own extent of significant low
// frequencies along each axis, so whether a coefficient is zero is told by a wider
// neighbourhood than the three nearest neighbours the narrow set looks at.
TEST(CoefCoderTest, WideContextsCodeBlocksWithVaryingExtentsInFewerBytes) {
  const BlockShape shape{16, 16, 16};
  SplitMix rng(5);
  std::vector<std::vector<int32_t>> blocks;
  for (int b = 0; b < 64; ++b) {
    std::vector<int32_t> block(static_cast<size_t>(shape.Volume()), 0);
    const int e0 = 2 + static_cast<int>(rng.Below(12)), e1 = 2 + static_cast<int>(rng.Below(12)),
              e2 = 2 + static_cast<int>(rng.Below(12));
    for (int i = 0; i < 16; ++i) {
      for (int j = 0; j < 16; ++j) {
        for (int k = 0; k < 16; ++k) {
          const bool inside = i < e0 && j < e1 && k < e2;
          if (rng.Below(100) >= (inside ? 60u : 2u)) continue;
          const int32_t magnitude =
              1 + static_cast<int32_t>(rng.Below(inside && i + j + k < 4 ? 6 : 2));
          block[static_cast<size_t>((i * 16 + j) * 16 + k)] = rng.Below(2) ? -magnitude : magnitude;
        }
      }
    }
    blocks.push_back(std::move(block));
  }
  const CodedBlocks narrow = Encode(shape, blocks, CoefContextSet::kNarrow);
  const CodedBlocks wide = Encode(shape, blocks, CoefContextSet::kWide);
  ExpectDecodes(shape, narrow, 127, CoefContextSet::kNarrow);
  ExpectDecodes(shape, wide, 127, CoefContextSet::kWide);
  EXPECT_LT(wide.bytes.size(), narrow.bytes.size() * 0.98);  // measured: 3.5% fewer
}

TEST(CoefCoderTest, ExtremeAndSixteenBitValues) {
  SplitMix rng(7);
  for (const BlockShape shape :
       {BlockShape{16, 16, 16}, BlockShape{1, 8, 8}, BlockShape{1, 1, 32}}) {
    for (int32_t max_abs : {1, 127, 32767}) {
      const size_t volume = static_cast<size_t>(shape.Volume());
      std::vector<std::vector<int32_t>> blocks;
      blocks.emplace_back(volume, max_abs);
      blocks.emplace_back(volume, -max_abs);
      blocks.emplace_back(volume, 0);
      for (size_t r = 0; r < volume; ++r) blocks.back()[r] = (r % 2) ? max_abs : -max_abs;
      for (int n = 0; n < 6; ++n) blocks.push_back(SparseBlock(rng, shape, max_abs));
      ExpectDecodes(shape, Encode(shape, std::move(blocks)), max_abs);
    }
  }
}

TEST(CoefCoderTest, LargeValuesUseEscapesWithinInt32) {
  const BlockShape shape{1, 2, 2};
  const std::vector<int32_t> block = {2147483647, -2147483647, 1 << 20, -16};
  ExpectDecodes(shape, Encode(shape, {block, block}), 2147483647);
}

TEST(CoefCoderTest, DecoderRejectsMagnitudeAboveBound) {
  const BlockShape shape{1, 8, 8};
  struct Case {
    int32_t value;
    int32_t max_abs;
  };
  for (const Case c : {Case{128, 127}, Case{-128, 127}, Case{2, 1}, Case{16, 15}, Case{15, 14},
                       Case{1, 0}, Case{40000, 32767}}) {
    std::vector<int32_t> block(64, 0);
    block[9] = c.value;
    const CodedBlocks coded = Encode(shape, {block});
    CoefContexts contexts;
    ASSERT_TRUE(contexts.Init(shape).ok());
    RangeDecoder decoder(coded.bytes.data(), coded.bytes.size());
    std::vector<int32_t> out(64);
    EXPECT_EQ(DecodeCoefBlock(decoder, contexts, c.max_abs, out.data()).code(), kErrCorrupt)
        << c.value << " " << c.max_abs;
  }
}

TEST(CoefCoderTest, AllZeroBlocksCostAlmostNothingOnceAdapted) {
  CoefContexts contexts;
  ASSERT_TRUE(contexts.Init(BlockShape{16, 16, 16}).ok());
  const std::vector<int32_t> zeros(4096, 0);
  RangeEncoder encoder;
  for (int n = 0; n < 200; ++n) EncodeCoefBlock(encoder, contexts, zeros.data());
  const uint64_t before = encoder.BitCount();
  constexpr int kBlocks = 10000;
  for (int n = 0; n < kBlocks; ++n) EncodeCoefBlock(encoder, contexts, zeros.data());
  const double bits_per_block = static_cast<double>(encoder.BitCount() - before) / kBlocks;
  EXPECT_LT(bits_per_block, 0.05);
}

TEST(CoefCoderTest, CompressesSparseBlocksNearOrderZeroEntropy) {
  // 70% all-zero blocks: far below the order-0 entropy of the int8 symbols, which ignores
  // the block structure.
  SplitMix rng(11);
  const BlockShape shape{16, 16, 16};
  std::vector<std::vector<int32_t>> blocks;
  std::vector<int64_t> histogram(256, 0);
  for (int n = 0; n < 60; ++n) {
    blocks.push_back(rng.Below(10) < 7 ? std::vector<int32_t>(4096, 0)
                                       : SparseBlock(rng, shape, 127));
    for (int32_t v : blocks.back()) ++histogram[static_cast<size_t>(v + 128)];
  }
  double entropy_bits = 0;
  const double total = 60.0 * 4096;
  for (int64_t count : histogram) {
    if (count > 0) entropy_bits -= static_cast<double>(count) * std::log2(count / total);
  }
  const CodedBlocks coded = Encode(shape, blocks);
  EXPECT_LT(8.0 * static_cast<double>(coded.bytes.size()), 0.9 * entropy_bits);
  ExpectDecodes(shape, coded, 127);
}

TEST(CoefCoderTest, ContextsResetReproducesTheStream) {
  SplitMix rng(5);
  const BlockShape shape{1, 8, 8};
  std::vector<std::vector<int32_t>> blocks;
  for (int n = 0; n < 30; ++n) blocks.push_back(SparseBlock(rng, shape, 127));
  CoefContexts contexts;
  ASSERT_TRUE(contexts.Init(shape).ok());
  std::vector<uint8_t> streams[2];
  for (auto& stream : streams) {
    contexts.Reset();
    RangeEncoder encoder;
    for (const auto& block : blocks) EncodeCoefBlock(encoder, contexts, block.data());
    stream = encoder.Finish();
  }
  EXPECT_EQ(streams[0], streams[1]);
}

TEST(CoefCoderTest, TruncatedStreamsAreRejected) {
  SplitMix rng(3);
  const BlockShape shape{4, 8, 8};
  std::vector<std::vector<int32_t>> blocks;
  for (int n = 0; n < 40; ++n) blocks.push_back(SparseBlock(rng, shape, 127));
  const CodedBlocks coded = Encode(shape, blocks);
  std::vector<int32_t> out(256);
  for (size_t size = 0; size < coded.bytes.size(); ++size) {
    const std::vector<uint8_t> prefix(coded.bytes.begin(),
                                      coded.bytes.begin() + static_cast<long>(size));
    CoefContexts contexts;
    ASSERT_TRUE(contexts.Init(shape).ok());
    RangeDecoder decoder(prefix.data(), prefix.size());
    Status status;
    for (size_t b = 0; b < blocks.size() && status.ok(); ++b) {
      status = DecodeCoefBlock(decoder, contexts, 127, out.data());
    }
    if (status.ok()) status = decoder.Finish();
    EXPECT_FALSE(status.ok()) << "prefix of " << size << " bytes accepted";
  }
}

TEST(CoefCoderTest, GarbageNeverCrashesAndRespectsBound) {
  std::mt19937 rng(99);
  for (const BlockShape shape :
       {BlockShape{16, 16, 16}, BlockShape{1, 8, 8}, BlockShape{1, 1, 1}}) {
    CoefContexts contexts;
    ASSERT_TRUE(contexts.Init(shape).ok());
    std::vector<int32_t> out(static_cast<size_t>(shape.Volume()));
    for (int trial = 0; trial < 300; ++trial) {
      std::vector<uint8_t> garbage(rng() % 200);
      for (uint8_t& b : garbage) b = static_cast<uint8_t>(rng());
      contexts.Reset();
      RangeDecoder decoder(garbage.data(), garbage.size());
      for (int b = 0; b < 20; ++b) {
        const Status status = DecodeCoefBlock(decoder, contexts, 127, out.data());
        if (!status.ok()) break;
        for (int32_t v : out) ASSERT_LE(std::abs(v), 127);
      }
    }
  }
}

// Pins the exact bitstream (range coder arithmetic, adaptation, contexts, scan, syntax) of one
// context set. If this changes, the format changed: bump the format version.
std::vector<uint8_t> PinnedStream(CoefContextSet set) {
  SplitMix rng(20240601);
  RangeEncoder encoder;
  for (const BlockShape shape :
       {BlockShape{16, 16, 16}, BlockShape{1, 8, 8}, BlockShape{1, 1, 32}, BlockShape{4, 8, 2}}) {
    CoefContexts contexts;
    EXPECT_TRUE(contexts.Init(shape, set).ok());
    for (int n = 0; n < 40; ++n) {
      const int32_t max_abs = n % 4 == 3 ? 32767 : 127;
      const std::vector<int32_t> block =
          rng.Below(3) == 0 ? std::vector<int32_t>(static_cast<size_t>(shape.Volume()), 0)
                            : SparseBlock(rng, shape, max_abs);
      EncodeCoefBlock(encoder, contexts, block.data());
    }
    encoder.EncodeGolomb(rng.Below(1000), 2);
    encoder.EncodeBypass(static_cast<uint32_t>(rng.Next()), 32);
  }
  return encoder.Finish();
}

TEST(CoefCoderTest, BitstreamIsPinned) {
  // Computed once from this implementation. The narrow set's values date from bitstream 1.0 and
  // must never change: 1.0-1.3 streams stay readable.
  const std::vector<uint8_t> narrow = PinnedStream(CoefContextSet::kNarrow);
  EXPECT_EQ(narrow.size(), 4967u);
  EXPECT_EQ(Fnv1a(narrow), 0x1a89b1221f7123fcull);
  const std::vector<uint8_t> wide = PinnedStream(CoefContextSet::kWide);
  EXPECT_EQ(wide.size(), 5071u);
  EXPECT_EQ(Fnv1a(wide), 0x3341e0f75ffd5aa3ull);
}

}  // namespace
}  // namespace ecrf
