// The neighbour context set (bitstream 1.5, SPEC.md 4.4 and 4.7): round trips over block grids,
// the gain it exists for, its pinned bitstream, and its bounds on hostile input.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <random>
#include <vector>

#include "format/coefficients/coef_coder.h"
#include "tests/common/coef_test_blocks.h"

namespace ecrf {
namespace {

using testing_blocks::AllValidShapes;
using testing_blocks::ExpectedEob;
using testing_blocks::Fnv1a;
using testing_blocks::SplitMix;

constexpr size_t kNoLimit = static_cast<size_t>(-1);

struct Grid {
  BlockShape shape;
  int blocks[3];
  int count() const { return blocks[0] * blocks[1] * blocks[2]; }
};

std::vector<uint8_t> EncodeGrid(const Grid& grid, const std::vector<std::vector<int32_t>>& blocks,
                                CoefContextSet set) {
  CoefContexts contexts;
  const Status status = set == CoefContextSet::kNeighbour
                            ? contexts.Init(grid.shape, set, grid.blocks, kNoLimit)
                            : contexts.Init(grid.shape, set);
  EXPECT_TRUE(status.ok()) << status.message();
  RangeEncoder encoder;
  for (const auto& block : blocks) EncodeCoefBlock(encoder, contexts, block.data());
  return encoder.Finish();
}

void ExpectDecodes(const Grid& grid, const std::vector<std::vector<int32_t>>& blocks,
                   const std::vector<uint8_t>& bytes, int32_t max_abs) {
  CoefContexts contexts;
  ASSERT_TRUE(contexts.Init(grid.shape, CoefContextSet::kNeighbour, grid.blocks, kNoLimit).ok());
  RangeDecoder decoder(bytes.data(), bytes.size());
  std::vector<int32_t> out(static_cast<size_t>(grid.shape.Volume()), 12345);
  for (size_t b = 0; b < blocks.size(); ++b) {
    int eob = -1;
    const Status status = DecodeCoefBlock(decoder, contexts, max_abs, out.data(), &eob);
    ASSERT_TRUE(status.ok()) << status.message() << " block " << b;
    ASSERT_EQ(out, blocks[b]) << "block " << b;
    ASSERT_EQ(eob, ExpectedEob(grid.shape, blocks[b])) << "block " << b;
  }
  EXPECT_TRUE(decoder.Finish().ok());
}

// Sparse, frequency-decaying blocks, a share of them all zero or extreme.
std::vector<std::vector<int32_t>> MixedBlocks(SplitMix& rng, const BlockShape& shape, int count,
                                              int32_t max_abs) {
  const size_t volume = static_cast<size_t>(shape.Volume());
  std::vector<std::vector<int32_t>> blocks;
  for (int b = 0; b < count; ++b) {
    std::vector<int32_t> block(volume, 0);
    switch (rng.Below(6)) {
      case 0:
        break;  // all zero
      case 1:
        for (auto& v : block) v = rng.Below(2) ? max_abs : -max_abs;
        break;
      case 2:
        block[volume - 1] = 1;  // eob = volume, the neighbours' slots hold a long block
        break;
      default:
        for (size_t r = 0; r < volume; ++r) {
          const uint32_t f = static_cast<uint32_t>(r % static_cast<size_t>(shape.n2) +
                                                   (r / static_cast<size_t>(shape.n2)) %
                                                       static_cast<size_t>(shape.n1) +
                                                   r / static_cast<size_t>(shape.n1 * shape.n2));
          if (rng.Below(100) >= 80 / (1 + f)) continue;
          const int32_t m = 1 + static_cast<int32_t>(rng.Below(1 + 20 / (1 + f)));
          block[r] = rng.Below(2) ? -m : m;
        }
    }
    blocks.push_back(std::move(block));
  }
  return blocks;
}

TEST(NeighbourContexts, RoundTripEveryShapeOnSeveralBlockGrids) {
  SplitMix rng(17);
  for (const BlockShape& shape : AllValidShapes()) {
    for (const Grid grid :
         {Grid{shape, {1, 1, 1}}, Grid{shape, {2, 3, 2}}, Grid{shape, {3, 1, 4}}}) {
      SCOPED_TRACE(testing::Message()
                   << shape.n0 << "x" << shape.n1 << "x" << shape.n2 << " grid " << grid.blocks[0]
                   << "x" << grid.blocks[1] << "x" << grid.blocks[2]);
      const int32_t max_abs = rng.Below(2) ? 127 : 32767;
      const auto blocks = MixedBlocks(rng, shape, grid.count(), max_abs);
      ExpectDecodes(grid, blocks, EncodeGrid(grid, blocks, CoefContextSet::kNeighbour), max_abs);
    }
  }
}

// A caller that codes more blocks than its grid declares wraps around to block 0's neighbours:
// encoder and decoder still agree.
TEST(NeighbourContexts, BlocksBeyondTheGridStillRoundTrip) {
  SplitMix rng(3);
  const Grid grid{BlockShape{4, 4, 4}, {2, 2, 2}};
  const auto blocks = MixedBlocks(rng, grid.shape, 3 * grid.count() + 1, 127);
  ExpectDecodes(grid, blocks, EncodeGrid(grid, blocks, CoefContextSet::kNeighbour), 127);
}

// Blocks like those of trained feature planes: which frequencies are significant is a property
// of the local scene content, shared by every channel block of a (b1, b2) column and by the
// columns around it, not a smooth function of the frequency that a block's own higher
// frequencies would tell. The neighbour set sees the co-located coefficients; the wide set sees
// one block at a time.
TEST(NeighbourContexts, CodeSpatiallyCoherentBlocksInFewerBytesThanTheWideSet) {
  SplitMix rng(29);
  const Grid grid{BlockShape{8, 8, 8}, {3, 8, 8}};
  // Two textures, each a random set of significant positions; the left and right halves of the
  // plane use one each, and empty space (a quarter of the columns) is zero.
  std::vector<uint8_t> texture[2];
  for (auto& t : texture) {
    t.assign(512, 0);
    for (int r = 0; r < 512; ++r) {
      const int f = r % 8 + (r / 8) % 8 + r / 64;
      t[static_cast<size_t>(r)] = rng.Below(100) < static_cast<uint32_t>(60 / (1 + f / 3));
    }
  }
  std::vector<std::vector<int32_t>> blocks;
  for (int b0 = 0; b0 < 3; ++b0) {
    for (int b1 = 0; b1 < 8; ++b1) {
      for (int b2 = 0; b2 < 8; ++b2) {
        std::vector<int32_t> block(512, 0);
        if (b1 >= 2) {
          const std::vector<uint8_t>& t = texture[b2 < 4 ? 0 : 1];
          for (int r = 0; r < 512; ++r) {
            if (!t[static_cast<size_t>(r)] || rng.Below(100) >= 85) continue;
            const int32_t m = 1 + static_cast<int32_t>(rng.Below(3));
            block[static_cast<size_t>(r)] = rng.Below(2) ? -m : m;
          }
        }
        blocks.push_back(std::move(block));
      }
    }
  }
  const std::vector<uint8_t> wide = EncodeGrid(grid, blocks, CoefContextSet::kWide);
  const std::vector<uint8_t> neighbour = EncodeGrid(grid, blocks, CoefContextSet::kNeighbour);
  ExpectDecodes(grid, blocks, neighbour, 127);
  EXPECT_LT(neighbour.size(), wide.size() * 0.9) <<  // measured: 6,824 against 8,353 bytes
      neighbour.size() << " vs " << wide.size();
}

// The exact bitstream of the neighbour set. If this changes, the format changed.
TEST(NeighbourContexts, BitstreamIsPinned) {
  SplitMix rng(20261127);
  std::vector<uint8_t> all;
  for (const Grid grid :
       {Grid{BlockShape{16, 16, 16}, {2, 2, 3}}, Grid{BlockShape{1, 8, 8}, {1, 4, 5}},
        Grid{BlockShape{4, 8, 2}, {3, 2, 2}}}) {
    const auto blocks = MixedBlocks(rng, grid.shape, grid.count(), 127);
    const std::vector<uint8_t> bytes = EncodeGrid(grid, blocks, CoefContextSet::kNeighbour);
    all.insert(all.end(), bytes.begin(), bytes.end());
  }
  EXPECT_EQ(all.size(), 12184u);
  EXPECT_EQ(Fnv1a(all), 0x163f203ae1d0d44full);
}

TEST(NeighbourContexts, InitChecksTheGridAndBoundsItsMemory) {
  CoefContexts contexts;
  const BlockShape shape{16, 16, 16};
  EXPECT_FALSE(contexts.Init(shape, CoefContextSet::kNeighbour).ok());  // no grid
  const int zero[3] = {1, 0, 1};
  EXPECT_FALSE(contexts.Init(shape, CoefContextSet::kNeighbour, zero, kNoLimit).ok());
  const int grid[3] = {4, 10, 12};
  const uint64_t bytes = NeighbourBytes(shape, grid);
  EXPECT_EQ(bytes, 10u * 12u * (4096u + 2u));
  const Status refused =
      contexts.Init(shape, CoefContextSet::kNeighbour, grid, static_cast<size_t>(bytes - 1));
  EXPECT_EQ(refused.code(), kErrLimit);
  EXPECT_TRUE(
      contexts.Init(shape, CoefContextSet::kNeighbour, grid, static_cast<size_t>(bytes)).ok());
  const CoefContextSet unknown = static_cast<CoefContextSet>(3);
  EXPECT_FALSE(contexts.Init(shape, unknown, grid, kNoLimit).ok());
}

TEST(NeighbourContexts, ResetReproducesTheStream) {
  SplitMix rng(8);
  const Grid grid{BlockShape{4, 8, 8}, {2, 3, 3}};
  const auto blocks = MixedBlocks(rng, grid.shape, grid.count(), 127);
  CoefContexts contexts;
  ASSERT_TRUE(contexts.Init(grid.shape, CoefContextSet::kNeighbour, grid.blocks, kNoLimit).ok());
  std::vector<uint8_t> streams[2];
  for (auto& stream : streams) {
    contexts.Reset();
    RangeEncoder encoder;
    for (const auto& block : blocks) EncodeCoefBlock(encoder, contexts, block.data());
    stream = encoder.Finish();
  }
  EXPECT_EQ(streams[0], streams[1]);
  EXPECT_EQ(streams[0], EncodeGrid(grid, blocks, CoefContextSet::kNeighbour));
}

TEST(NeighbourContexts, GarbageNeverCrashesAndRespectsTheBound) {
  std::mt19937 rng(99);
  for (const Grid grid :
       {Grid{BlockShape{16, 16, 16}, {2, 3, 3}}, Grid{BlockShape{1, 8, 8}, {1, 5, 4}},
        Grid{BlockShape{1, 1, 1}, {3, 3, 3}}}) {
    CoefContexts contexts;
    ASSERT_TRUE(contexts.Init(grid.shape, CoefContextSet::kNeighbour, grid.blocks, kNoLimit).ok());
    std::vector<int32_t> out(static_cast<size_t>(grid.shape.Volume()));
    for (int trial = 0; trial < 300; ++trial) {
      std::vector<uint8_t> garbage(rng() % 300);
      for (uint8_t& b : garbage) b = static_cast<uint8_t>(rng());
      contexts.Reset();
      RangeDecoder decoder(garbage.data(), garbage.size());
      for (int b = 0; b < grid.count() + 5; ++b) {
        const Status status = DecodeCoefBlock(decoder, contexts, 127, out.data());
        if (!status.ok()) break;
        for (int32_t v : out) ASSERT_LE(std::abs(v), 127);
      }
    }
  }
}

}  // namespace
}  // namespace ecrf
