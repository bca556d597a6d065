#include "trainer/model/alpha_mask.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

namespace ecrf {
namespace trainer {
namespace {

Aabb Box() {
  Aabb box;
  box.min = {-0.7f, -1.1f, 0.2f};
  box.max = {0.9f, 0.4f, 1.9f};
  return box;
}

AlphaMask RandomMask(const std::array<int, 3>& res, double share, uint32_t seed) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution occupied(share);
  std::vector<uint8_t> occ(size_t(res[0]) * res[1] * res[2]);
  for (uint8_t& v : occ) v = occupied(rng) ? 1 : 0;
  return AlphaMask(Box(), res, std::move(occ));
}

// A point of the box at fractional grid coordinates f (0..res-1 per axis).
std::array<float, 3> At(const AlphaMask& mask, const double f[3]) {
  std::array<float, 3> p;
  for (int a = 0; a < 3; ++a) {
    const double t = f[a] / (mask.res()[a] - 1);
    p[a] = float(mask.aabb().min[a] * (1.0 - t) + mask.aabb().max[a] * t);
  }
  return p;
}

// Occupied is Sample() > 0 (TensoRF's rule) at random points, on cell corners, faces and
// edges, and outside the box, for masks from nearly empty to half full: its shortcuts (the
// per-cell and per-block tables) only ever answer what the interpolation would.
TEST(AlphaMask, OccupiedIsPositiveInterpolatedOccupancy) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-0.1, 1.1);
  for (const double share : {0.0005, 0.02, 0.5}) {
    const AlphaMask mask = RandomMask({37, 22, 29}, share, 4);
    int occupied = 0;
    for (int i = 0; i < 200000; ++i) {
      double f[3];
      for (int a = 0; a < 3; ++a) {
        f[a] = u(rng) * (mask.res()[a] - 1);
        if (i % 3 == 0) f[a] = std::round(f[a]);  // on grid points, edges and faces
      }
      const std::array<float, 3> p = At(mask, f);
      const bool want = mask.Sample(p.data()) > 0.f;
      ASSERT_EQ(mask.Occupied(p.data()), want) << f[0] << " " << f[1] << " " << f[2];
      occupied += want;
    }
    EXPECT_GT(occupied, 0) << share;
    EXPECT_LT(occupied, 200000) << share;
  }
}

TEST(AlphaMaskRes, MaskPointsAtMostDownscaleCellsApart) {
  EXPECT_EQ(AlphaMaskRes({21, 21, 21}, 1), (std::array<int, 3>{21, 21, 21}));
  EXPECT_EQ(AlphaMaskRes({21, 21, 21}, 2), (std::array<int, 3>{11, 11, 11}));
  EXPECT_EQ(AlphaMaskRes({190, 195, 285}, 2), (std::array<int, 3>{96, 98, 143}));
  EXPECT_EQ(AlphaMaskRes({190, 195, 285}, 3), (std::array<int, 3>{64, 66, 96}));
  EXPECT_EQ(AlphaMaskRes({2, 3, 5}, 16), (std::array<int, 3>{2, 2, 2}));
  EXPECT_THROW(AlphaMaskRes({8, 8, 8}, 0), std::invalid_argument);
}

// The coarse mask keeps every point the fine mask keeps (random points, and points on the fine
// grid's points, edges and faces, where the trilinear support changes), and is not full.
TEST(CoarsenAlphaMask, KeepsEveryPointTheFineMaskKeeps) {
  const std::array<int, 3> res = {23, 17, 30};
  for (int downscale : {2, 3, 5}) {
    const AlphaMask fine = RandomMask(res, 0.002, 7u + uint32_t(downscale));
    ASSERT_FALSE(fine.empty());
    const AlphaMask coarse = CoarsenAlphaMask(fine, downscale);
    EXPECT_EQ(coarse.res(), AlphaMaskRes(res, downscale));
    EXPECT_EQ(coarse.aabb().min, fine.aabb().min);
    EXPECT_EQ(coarse.aabb().max, fine.aabb().max);
    EXPECT_LT(coarse.count(), coarse.occupancy().size()) << downscale;
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::uniform_int_distribution<int> half(0, 2);
    int kept = 0;
    for (int i = 0; i < 400000; ++i) {
      double f[3];
      for (int a = 0; a < 3; ++a) {
        const double x = u(rng) * (res[a] - 1);
        // A third of the coordinates on a fine grid plane or midway between two.
        const int mode = half(rng);
        f[a] = mode == 0 ? x : (mode == 1 ? double(int(x)) : int(x) + 0.5);
      }
      const std::array<float, 3> p = At(fine, f);
      if (!fine.Occupied(p.data())) continue;
      ++kept;
      ASSERT_TRUE(coarse.Occupied(p.data()))
          << "downscale " << downscale << " at " << f[0] << " " << f[1] << " " << f[2];
    }
    EXPECT_GT(kept, 1000) << downscale;
  }
}

TEST(CoarsenAlphaMask, MarksOnlyTheCornersOfTheCellsHoldingAPoint) {
  const std::array<int, 3> res = {9, 9, 9};  // downscale 2: coarse points on even fine points
  std::vector<uint8_t> occ(9 * 9 * 9, 0);
  occ[(size_t(4) * 9 + 4) * 9 + 4] = 1;  // on coarse point (2, 2, 2)
  EXPECT_EQ(CoarsenAlphaMask(AlphaMask(Box(), res, occ), 2).count(), 1u);
  occ.assign(occ.size(), 0);
  occ[(size_t(3) * 9 + 3) * 9 + 3] = 1;  // inside coarse cell (1, 1, 1)
  const AlphaMask inside = CoarsenAlphaMask(AlphaMask(Box(), res, occ), 2);
  EXPECT_EQ(inside.count(), 8u);
  for (int z = 1; z <= 2; ++z)
    for (int y = 1; y <= 2; ++y)
      for (int x = 1; x <= 2; ++x) EXPECT_EQ(inside.occupancy()[(size_t(z) * 5 + y) * 5 + x], 1);
  occ.assign(occ.size(), 0);
  occ[(size_t(4) * 9 + 3) * 9 + 4] = 1;  // on a coarse edge: x and z on coarse points
  EXPECT_EQ(CoarsenAlphaMask(AlphaMask(Box(), res, occ), 2).count(), 2u);
  // Downscale 1 is the fine mask itself.
  const AlphaMask fine = RandomMask({12, 7, 10}, 0.05, 5u);
  EXPECT_EQ(CoarsenAlphaMask(fine, 1).occupancy(), fine.occupancy());
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
