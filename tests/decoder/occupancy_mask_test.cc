// The occupancy mask's acceleration levels (decoder/field.h): built from the set voxels only, they
// must still mark exactly the blocks whose closed corner range holds a set voxel, whatever the
// mask's size (bits past the last voxel, resolutions that are not a multiple of the block size).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <random>
#include <vector>

#include "decoder/field.h"

namespace ecrf {
namespace dec {
namespace {

struct MaskCase {
  int res[3];
  double density;  // share of voxels set
};

// Every block of every level against the definition: empty iff no set voxel lies in the closed
// range [b * B, min((b + 1) * B, res - 1)] on every axis.
void ExpectLevelsMatchTheDefinition(const OccupancyMask& mask, const std::vector<char>& set) {
  const int* res = mask.res();
  auto voxel = [&](int x, int y, int z) {
    return set[(static_cast<size_t>(z) * res[1] + y) * res[0] + x] != 0;
  };
  for (int level = 0; level < OccupancyMask::kLevels; ++level) {
    const int B = OccupancyMask::kBlock[level];
    for (int bz = 0; bz * B < res[2] - 1; ++bz) {
      for (int by = 0; by * B < res[1] - 1; ++by) {
        for (int bx = 0; bx * B < res[0] - 1; ++bx) {
          const int b[3] = {bx, by, bz};
          int lo[3], hi[3];
          bool any = false;
          for (int a = 0; a < 3; ++a) {
            lo[a] = b[a] * B;
            hi[a] = std::min(lo[a] + B, res[a] - 1);
          }
          for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
              for (int x = lo[0]; x <= hi[0]; ++x) any |= voxel(x, y, z);
          const float idx[3] = {static_cast<float>(lo[0]) + 0.5f, static_cast<float>(lo[1]) + 0.5f,
                                static_cast<float>(lo[2]) + 0.5f};
          int got_lo[3], got_hi[3];
          EXPECT_EQ(mask.EmptyBlock(level, idx, got_lo, got_hi), !any)
              << "level " << level << " block " << bx << "," << by << "," << bz;
          for (int a = 0; a < 3; ++a) {
            EXPECT_EQ(got_lo[a], lo[a]);
            EXPECT_EQ(got_hi[a], hi[a]);
          }
        }
      }
    }
  }
}

// A mask over [-1, 1]^3 whose voxels are set with probability c.density, its acceleration built;
// `set` holds the voxels (x fastest).
struct RandomMask {
  OccupancyMask mask;
  std::vector<char> set;
  RandomMask(const MaskCase& c, std::mt19937& rng) {
    const float lo[3] = {-1.f, -1.f, -1.f}, hi[3] = {1.f, 1.f, 1.f};
    EXPECT_TRUE(mask.Init(lo, hi, c.res).ok());
    set.assign(mask.voxel_count(), 0);
    std::bernoulli_distribution on(c.density);
    for (int z = 0; z < c.res[2]; ++z)
      for (int y = 0; y < c.res[1]; ++y)
        for (int x = 0; x < c.res[0]; ++x) {
          const bool v = on(rng);
          set[(static_cast<size_t>(z) * c.res[1] + y) * c.res[0] + x] = v;
          if (v) mask.Set(x, y, z, true);
        }
    EXPECT_TRUE(mask.BuildAcceleration().ok());
  }
};

testing::Message Name(const MaskCase& c) {
  return testing::Message() << c.res[0] << "x" << c.res[1] << "x" << c.res[2];
}

TEST(OccupancyMask, LevelsFromTheSetVoxelsMatchTheDefinition) {
  const MaskCase cases[] = {
      {{7, 13, 33}, 0.02},  {{17, 5, 9}, 0.3},       {{33, 33, 2}, 0.0},
      {{2, 2, 2}, 1.0},     {{19, 23, 29}, 0.005},   {{64, 3, 5}, 1.0},
      {{9, 17, 65}, 0.001}, {{150, 70, 20}, 0.0004}, {{130, 129, 3}, 0.002},
  };
  std::mt19937 rng(5);
  for (const MaskCase& c : cases) {
    SCOPED_TRACE(Name(c));
    const RandomMask m(c, rng);
    EXPECT_EQ(m.mask.occupied_count(),
              static_cast<size_t>(std::count(m.set.begin(), m.set.end(), 1)));
    ExpectLevelsMatchTheDefinition(m.mask, m.set);
  }
}

// The empty cube around every empty finest block against a brute-force chessboard distance to the
// nearest occupied finest block: its radius is exactly min(d - 1, kEmptyRadiusCap), so the cube
// holds no occupied block and is as large as the cap allows.
TEST(OccupancyMask, EmptyCubeIsTheLargestEmptyCubeUpToTheCap) {
  constexpr int L = OccupancyMask::kLevels - 1, B = OccupancyMask::kBlock[L];
  const MaskCase cases[] = {{{97, 61, 45}, 0.00005},
                            {{41, 130, 23}, 0.0002},
                            {{150, 9, 70}, 0.00002},
                            {{33, 33, 2}, 0.0}};
  std::mt19937 rng(11);
  for (const MaskCase& c : cases) {
    SCOPED_TRACE(Name(c));
    const RandomMask m(c, rng);
    const OccupancyMask& mask = m.mask;
    struct Block {
      int b[3];
      bool empty;
      int lo[3], hi[3];  // its closed range, from EmptyBlock
    };
    std::vector<Block> blocks;
    for (int bz = 0; bz * B < c.res[2] - 1; ++bz)
      for (int by = 0; by * B < c.res[1] - 1; ++by)
        for (int bx = 0; bx * B < c.res[0] - 1; ++bx) {
          Block k = {{bx, by, bz}, false, {}, {}};
          float idx[3];
          for (int a = 0; a < 3; ++a) idx[a] = static_cast<float>(k.b[a] * B) + 0.5f;
          k.empty = mask.EmptyBlock(L, idx, k.lo, k.hi);
          blocks.push_back(k);
        }
    int widened = 0;
    bool any_occupied = false;
    for (Block& k : blocks) {
      if (!k.empty) {
        any_occupied = true;
        continue;
      }
      int d = 1 << 20;
      for (const Block& o : blocks) {
        if (o.empty) continue;
        d = std::min(d, std::max({std::abs(o.b[0] - k.b[0]), std::abs(o.b[1] - k.b[1]),
                                  std::abs(o.b[2] - k.b[2])}));
      }
      const int radius = std::min(d - 1, OccupancyMask::kEmptyRadiusCap);
      EXPECT_EQ(mask.EmptyCube(k.lo, k.hi), radius);
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(k.lo[a], std::max(0, (k.b[a] - radius) * B))
            << k.b[0] << "," << k.b[1] << "," << k.b[2];
        EXPECT_EQ(k.hi[a], std::min((k.b[a] + radius + 1) * B, c.res[a] - 1));
      }
      widened += radius > 0;
    }
    EXPECT_GT(widened, 0);
    EXPECT_EQ(any_occupied, c.density > 0);
  }
}

}  // namespace
}  // namespace dec
}  // namespace ecrf
