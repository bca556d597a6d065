#include "trainer/model/tensorf_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace ecrf {
namespace trainer {
namespace {

TensorfConfig SmallConfig() {
  TensorfConfig c;
  c.density_ranks = {2, 2, 2};
  c.app_ranks = {3, 3, 3};
  c.head.num_products = 9;
  c.head.hidden = 16;
  c.aabb.min = {-1.f, -1.f, -1.f};
  c.aabb.max = {1.f, 1.f, 1.f};
  return c;
}

// Density field = shift_compensation * bump(x,y) * bump(z) via rank 0 of mode 0 only.
void MakeBlob(TensorfModel& model, float cx, float cy, float cz, float radius, float height) {
  VmGrid& g = model.density();
  std::fill(g.params().begin(), g.params().end(), 0.f);
  const auto& res = model.res();
  const Aabb& box = model.aabb();
  auto world = [&](int a, int i) {
    return box.min[a] + (box.max[a] - box.min[a]) * static_cast<float>(i) / (res[a] - 1);
  };
  for (int y = 0; y < res[1]; ++y)
    for (int x = 0; x < res[0]; ++x) {
      const float dx = world(0, x) - cx, dy = world(1, y) - cy;
      g.PlaneAt(0, y, x, 0) = (dx * dx + dy * dy < radius * radius) ? height : 0.f;
    }
  for (int z = 0; z < res[2]; ++z) {
    const float dz = world(2, z) - cz;
    g.LineAt(0, z, 0) = std::fabs(dz) < radius ? 1.f : 0.f;
  }
}

TEST(TensorfModelTest, InitializeGeometry) {
  TensorfConfig c = SmallConfig();
  TensorfModel model(c);
  model.Initialize({6, 7, 8}, 3);
  EXPECT_EQ(model.res(), (std::array<int, 3>{6, 7, 8}));
  EXPECT_FLOAT_EQ(model.units()[0], 2.f / 5);
  EXPECT_FLOAT_EQ(model.units()[2], 2.f / 7);
  EXPECT_NEAR(model.step_size(), (2.f / 5 + 2.f / 6 + 2.f / 7) / 3 * 0.5f, 1e-6);
  EXPECT_EQ(model.n_samples(), static_cast<int>(std::sqrt(36.0 + 49 + 64) / 0.5));
  EXPECT_EQ(CalNSamples({128, 128, 128}, 0.5f), 443);
  EXPECT_EQ(model.alpha_mask(), nullptr);
  auto named = model.NamedParameters();
  ASSERT_EQ(named.size(), 13u);
  size_t total = 0;
  for (const auto& a : named) {
    size_t prod = 1;
    for (auto s : a.shape) prod *= s;
    EXPECT_EQ(prod, a.size) << a.name;
    total += a.size;
  }
  EXPECT_EQ(total, model.density().params().size() + model.appearance().params().size() +
                       model.head().params().size());
  EXPECT_EQ(named[0].name, "density.plane.0");
  EXPECT_EQ(named[0].shape, (std::vector<int64_t>{7, 6, 2}));
  EXPECT_EQ(named[12].name, "head");
  TensorfConfig bad = c;
  bad.head.num_products = 10;
  EXPECT_THROW(TensorfModel m(bad), std::runtime_error);
}

TEST(TensorfModelTest, UpsampleKeepsLinearField) {
  TensorfModel model(SmallConfig());
  model.Initialize({5, 6, 7}, 1);
  // Plane linear in the coordinates, line constant -> density linear -> preserved exactly.
  VmGrid& g = model.density();
  std::fill(g.params().begin(), g.params().end(), 0.f);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 5; ++x) g.PlaneAt(0, y, x, 0) = 0.5f + 0.3f * x / 4.f - 0.6f * y / 5.f;
  for (int z = 0; z < 7; ++z) g.LineAt(0, z, 0) = 2.f;
  std::vector<float> before;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::vector<std::array<float, 3>> pts(100);
  for (auto& p : pts) p = {u(rng), u(rng), u(rng)};
  for (auto& p : pts) before.push_back(model.Sigma(p.data()));
  model.UpsampleTo({11, 9, 13});
  EXPECT_EQ(model.n_samples(), static_cast<int>(std::sqrt(121.0 + 81 + 169) / 0.5));
  EXPECT_FLOAT_EQ(model.units()[0], 0.2f);
  for (size_t i = 0; i < pts.size(); ++i) EXPECT_NEAR(model.Sigma(pts[i].data()), before[i], 1e-5);
}

TEST(TensorfModelTest, AlphaMaskOfEmptyFieldIsEmpty) {
  TensorfModel model(SmallConfig());
  model.Initialize({16, 16, 16}, 2);
  std::fill(model.density().params().begin(), model.density().params().end(), 0.f);
  const Aabb box = model.UpdateAlphaMask({16, 16, 16});
  ASSERT_NE(model.alpha_mask(), nullptr);
  EXPECT_TRUE(model.alpha_mask()->empty());
  EXPECT_EQ(box.min, model.aabb().min);
  EXPECT_EQ(box.max, model.aabb().max);
  const float p[3] = {0.f, 0.f, 0.f};
  EXPECT_FALSE(model.alpha_mask()->Occupied(p));
}

TEST(TensorfModelTest, AlphaMaskCoversBlobAndShrinkKeepsValues) {
  TensorfConfig c = SmallConfig();
  TensorfModel model(c);
  model.Initialize({21, 21, 21}, 2);
  MakeBlob(model, 0.2f, -0.1f, 0.3f, 0.35f, 5.f);  // feature 5 inside -> sigma ~ softplus(-5)
  // sigma inside = softplus(5 - 10) = 6.7e-3; alpha = 1 - exp(-sigma*step) ~ 3.4e-4 >= 1e-4.
  const Aabb box = model.UpdateAlphaMask({21, 21, 21});
  const AlphaMask* mask = model.alpha_mask();
  ASSERT_NE(mask, nullptr);
  EXPECT_FALSE(mask->empty());
  // Every point of the blob is covered; far away points are not.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  int inside_checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const float p[3] = {u(rng), u(rng), u(rng)};
    const float dx = p[0] - 0.2f, dy = p[1] + 0.1f, dz = p[2] - 0.3f;
    if (model.Sigma(p) > 1e-3f) {
      ++inside_checked;
      ASSERT_TRUE(mask->Occupied(p)) << p[0] << " " << p[1] << " " << p[2];
    }
    if (std::sqrt(dx * dx + dy * dy) > 0.35f + 0.3f || std::fabs(dz) > 0.35f + 0.3f) {
      ASSERT_FALSE(mask->Occupied(p));
    }
  }
  EXPECT_GT(inside_checked, 100);
  // Box: blob extent dilated by one voxel (0.1) on the grid (+ interpolation support).
  for (int a = 0; a < 3; ++a) {
    const float centre = a == 0 ? 0.2f : (a == 1 ? -0.1f : 0.3f);
    EXPECT_LE(box.min[a], centre - 0.3f);
    EXPECT_GE(box.min[a], centre - 0.35f - 0.21f);
    EXPECT_GE(box.max[a], centre + 0.3f);
    EXPECT_LE(box.max[a], centre + 0.35f + 0.21f);
  }
  // Shrink with mask res == res: aabb = box (on vertices), values preserved at world points.
  std::vector<std::array<float, 3>> pts;
  for (int i = 0; i < 200; ++i) {
    std::array<float, 3> p;
    for (int a = 0; a < 3; ++a)
      p[a] = box.min[a] + (box.max[a] - box.min[a]) * (0.5f * (u(rng) + 1.f));
    pts.push_back(p);
  }
  std::vector<float> before;
  for (auto& p : pts) before.push_back(model.Sigma(p.data()));
  const std::array<int, 3> old_res = model.res();
  model.Shrink(box);
  for (int a = 0; a < 3; ++a) {
    EXPECT_LT(model.res()[a], old_res[a]);
    EXPECT_NEAR(model.aabb().min[a], box.min[a], 1e-6);
    EXPECT_NEAR(model.units()[a], 0.1f, 1e-5);
  }
  for (size_t i = 0; i < pts.size(); ++i) EXPECT_NEAR(model.Sigma(pts[i].data()), before[i], 1e-5);
}

TEST(TensorfModelTest, ShrinkWithoutMaskSnapsToVertices) {
  TensorfModel model(SmallConfig());
  model.Initialize({11, 9, 13}, 5);
  Aabb target;
  target.min = {-0.53f, -0.2f, 0.1f};
  target.max = {0.47f, 0.81f, 0.98f};
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  std::vector<std::array<float, 3>> pts;
  for (int i = 0; i < 200; ++i) {
    std::array<float, 3> p;
    for (int a = 0; a < 3; ++a) p[a] = target.min[a] + (target.max[a] - target.min[a]) * u(rng);
    pts.push_back(p);
  }
  std::vector<float> before;
  for (auto& p : pts) before.push_back(model.Sigma(p.data()));
  model.Shrink(target);
  // units x = 0.2: tl = round(0.47/0.2) = 2, br = round(1.47/0.2) + 1 = 8 -> vertices 2..7,
  // i.e. [-0.6, 0.4], res 6.
  EXPECT_EQ(model.res()[0], 6);
  EXPECT_NEAR(model.aabb().min[0], -0.6f, 1e-6);
  EXPECT_NEAR(model.aabb().max[0], 0.4f, 1e-6);
  for (int a = 0; a < 3; ++a) {
    EXPECT_LE(model.aabb().min[a], target.min[a] + model.units()[a] / 2 + 1e-6f);
    EXPECT_GE(model.aabb().max[a], target.max[a] - model.units()[a] / 2 - 1e-6f);
  }
  // Points inside the new box keep their values.
  for (size_t i = 0; i < pts.size(); ++i) {
    bool inside = true;
    for (int a = 0; a < 3; ++a)
      inside &= pts[i][a] >= model.aabb().min[a] && pts[i][a] <= model.aabb().max[a];
    if (inside) EXPECT_NEAR(model.Sigma(pts[i].data()), before[i], 1e-5);
  }
}

TEST(TensorfModelTest, FilterRays) {
  TensorfConfig c = SmallConfig();
  c.near = 0.f;  // the third ray starts inside the box
  TensorfModel model(c);
  model.Initialize({21, 21, 21}, 2);
  const float o[] = {-3.f, 0.f, 0.f, -3.f, 3.f, 0.f, 0.f, 0.f, 0.f, -3.f, 0.6f, 0.3f};
  const float d[] = {1.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 0.f, 1.f, 1.f, 0.f, 0.f};
  auto keep = model.FilterRays(4, o, d, true);
  EXPECT_EQ(keep, (std::vector<uint8_t>{1, 0, 1, 1}));
  // With a mask holding a blob at the centre only rays through it survive.
  MakeBlob(model, 0.f, 0.f, 0.f, 0.3f, 5.f);
  model.UpdateAlphaMask({21, 21, 21});
  keep = model.FilterRays(4, o, d, false);
  EXPECT_EQ(keep, (std::vector<uint8_t>{1, 0, 1, 0}));
  // Equals brute force over all n_samples samples (the implementation skips the range outside
  // the mask box) for random rays, after a shrink so the mask box is larger than the aabb.
  model.Shrink(model.UpdateAlphaMask({21, 21, 21}));
  std::mt19937 rng(5);
  std::normal_distribution<float> nd;
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  const int n = 3000;
  std::vector<float> ro(3 * n), rd(3 * n);
  for (int i = 0; i < n; ++i) {
    float dir[3];
    for (int a = 0; a < 3; ++a) {
      ro[3 * i + a] = 2.5f * nd(rng) / 1.7f;
      dir[a] = u(rng) - ro[3 * i + a];
    }
    const float l = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (int a = 0; a < 3; ++a) rd[3 * i + a] = dir[a] / l;
  }
  keep = model.FilterRays(n, ro.data(), rd.data(), false, 256);
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    float te, tx;
    RayAabb(model.aabb(), &ro[3 * i], &rd[3 * i], &te, &tx);
    const float t_min = std::min(std::max(te, model.config().near), model.config().far);
    uint8_t hit = 0;
    for (int s = 0; s < 256; ++s) {
      const float t = t_min + model.step_size() * static_cast<float>(s);
      const float p[3] = {ro[3 * i] + rd[3 * i] * t, ro[3 * i + 1] + rd[3 * i + 1] * t,
                          ro[3 * i + 2] + rd[3 * i + 2] * t};
      hit |= model.alpha_mask()->Occupied(p) ? 1 : 0;
    }
    ASSERT_EQ(keep[i], hit) << i;
    kept += hit;
  }
  EXPECT_GT(kept, 100);
  EXPECT_LT(kept, n - 100);
}

TEST(TensorfModelTest, DensityL1AddsWeightedGradient) {
  TensorfModel model(SmallConfig());
  model.Initialize({4, 4, 4}, 9);
  model.ZeroGrads();
  const double v = model.DensityL1(2.f);
  EXPECT_GT(v, 0.0);
  const auto& g = model.density().grads();
  const auto& p = model.density().params();
  const float expect = 2.f / model.density().plane_size(0);
  EXPECT_NEAR(std::fabs(g[0]), expect, 1e-7);
  EXPECT_EQ(g[0] > 0, p[0] > 0);
  for (float x : model.appearance().grads()) ASSERT_EQ(x, 0.f);
}

TEST(TensorfModelTest, CopyIsDeep) {
  TensorfModel a(SmallConfig());
  a.Initialize({4, 4, 4}, 1);
  TensorfModel b = a;
  b.density().params()[0] += 1.f;
  EXPECT_NE(a.density().params()[0], b.density().params()[0]);
  b = a;
  EXPECT_EQ(a.density().params(), b.density().params());
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
