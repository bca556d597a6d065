#include "trainer/model/vm_grid.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <random>
#include <vector>

namespace ecrf {
namespace trainer {
namespace {

// Independent double-precision grid_sample(align_corners=True, zero padding) on a
// channels-last plane [H][W][R] at (x -> W, y -> H).
double RefPlane(const VmGrid& g, int m, int r, double cx, double cy) {
  const int W = g.res()[kMatMode[m][0]], H = g.res()[kMatMode[m][1]], R = g.ranks()[m];
  const double ix = (cx + 1) / 2 * (W - 1), iy = (cy + 1) / 2 * (H - 1);
  const int x0 = static_cast<int>(std::floor(ix)), y0 = static_cast<int>(std::floor(iy));
  double v = 0;
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) {
      const int x = x0 + dx, y = y0 + dy;
      if (x < 0 || y < 0 || x >= W || y >= H) continue;
      const double w = (dx ? ix - x0 : 1 - (ix - x0)) * (dy ? iy - y0 : 1 - (iy - y0));
      v += w * g.plane(m)[(static_cast<size_t>(y) * W + x) * R + r];
    }
  return v;
}
double RefLine(const VmGrid& g, int m, int r, double c) {
  const int L = g.res()[kVecMode[m]], R = g.ranks()[m];
  const double i = (c + 1) / 2 * (L - 1);
  const int i0 = static_cast<int>(std::floor(i));
  double v = 0;
  for (int d = 0; d < 2; ++d) {
    const int k = i0 + d;
    if (k < 0 || k >= L) continue;
    v += (d ? i - i0 : 1 - (i - i0)) * g.line(m)[static_cast<size_t>(k) * R + r];
  }
  return v;
}

VmGrid MakeGrid(std::array<int, 3> res, std::array<int, 3> ranks, uint64_t seed) {
  VmGrid g;
  g.Allocate(res, ranks);
  g.InitNormal(0.5f, seed);
  return g;
}

std::vector<std::array<float, 3>> RandomPoints(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::vector<std::array<float, 3>> pts(n);
  for (auto& p : pts) p = {u(rng), u(rng), u(rng)};
  return pts;
}

TEST(VmGridTest, LayoutAndInit) {
  VmGrid g = MakeGrid({5, 6, 7}, {2, 3, 4}, 1);
  EXPECT_EQ(g.plane_size(0), 6u * 5 * 2);  // [res_y][res_x][R]
  EXPECT_EQ(g.plane_size(1), 7u * 5 * 3);  // [res_z][res_x][R]
  EXPECT_EQ(g.plane_size(2), 7u * 6 * 4);  // [res_z][res_y][R]
  EXPECT_EQ(g.line_size(0), 7u * 2);       // z
  EXPECT_EQ(g.line_size(1), 6u * 3);       // y
  EXPECT_EQ(g.line_size(2), 5u * 4);       // x
  EXPECT_EQ(g.params().size(), g.line_offset(2) + g.line_size(2));
  EXPECT_EQ(g.total_rank(), 9);
  double mean = 0, sq = 0;
  for (float v : g.params()) {
    mean += v;
    sq += v * v;
  }
  mean /= g.params().size();
  sq /= g.params().size();
  EXPECT_NEAR(mean, 0.0, 0.1);
  EXPECT_NEAR(std::sqrt(sq), 0.5, 0.08);
  VmGrid g2 = MakeGrid({5, 6, 7}, {2, 3, 4}, 1);
  EXPECT_EQ(g.params(), g2.params());
}

TEST(VmGridTest, SamplingMatchesReferenceGridSample) {
  VmGrid g = MakeGrid({6, 7, 5}, {3, 2, 4}, 7);
  auto pts = RandomPoints(200, 3);
  // Include the box corners and faces (index exactly size-1).
  pts.push_back({1.f, 1.f, 1.f});
  pts.push_back({-1.f, -1.f, -1.f});
  pts.push_back({1.f, -0.3f, 0.2f});
  std::vector<float> prod(g.total_rank());
  for (const auto& p : pts) {
    GridPoint gp;
    LocateGridPoint(p.data(), g.res(), &gp);
    double dens = 0;
    for (int m = 0; m < 3; ++m) {
      for (int r = 0; r < g.ranks()[m]; ++r) {
        const double pv = RefPlane(g, m, r, p[kMatMode[m][0]], p[kMatMode[m][1]]);
        const double lv = RefLine(g, m, r, p[kVecMode[m]]);
        dens += pv * lv;
        g.Products(gp, prod.data());
        EXPECT_NEAR(prod[g.rank_offset(m) + r], pv * lv, 1e-5);
      }
    }
    EXPECT_NEAR(g.Density(gp), dens, 1e-5);
  }
}

// L(params) = sum_k a_k Density(x_k) + sum_k b_k . Products(x_k) is linear in every single
// entry, so central differences are exact up to rounding: checks the scatter (incl. its vertex
// cache, with non-monotone point sequences) for every entry of the grid.
void CheckScatterAgainstFd(int threads) {
  VmGrid g = MakeGrid({6, 5, 7}, {2, 3, 4}, 11);
  auto pts = RandomPoints(40, 5);
  // Points on vertices / cell faces exercise zero-weight corners.
  pts.push_back({-1.f, -1.f, -1.f});
  pts.push_back({1.f, 1.f, 1.f});
  pts.push_back({0.2f, -1.f, 1.f});
  std::mt19937 rng(9);
  std::normal_distribution<float> nd;
  std::vector<float> a(pts.size());
  std::vector<float> b(pts.size() * g.total_rank());
  for (auto& v : a) v = nd(rng);
  for (auto& v : b) v = nd(rng);
  auto loss = [&](const VmGrid& grid) {
    double L = 0;
    std::vector<float> prod(grid.total_rank());
    for (size_t k = 0; k < pts.size(); ++k) {
      GridPoint gp;
      LocateGridPoint(pts[k].data(), grid.res(), &gp);
      L += static_cast<double>(a[k]) * grid.Density(gp);
      grid.Products(gp, prod.data());
      for (int r = 0; r < grid.total_rank(); ++r)
        L += static_cast<double>(b[k * grid.total_rank() + r]) * prod[r];
    }
    return L;
  };
  g.ZeroGrads();
  const int n = static_cast<int>(pts.size());
  // One task per mode, spread over threads (each task is the only writer of its plane and line).
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
  for (int m = 0; m < 3; ++m) {
    ModeGradScatter s;
    s.Bind(&g, m);
    for (int k = 0; k < n; ++k) {
      GridPoint gp;
      LocateGridPoint(pts[k].data(), g.res(), &gp);
      s.AddDensity(gp, a[k]);
      s.AddProducts(gp, b.data() + static_cast<size_t>(k) * g.total_rank() + g.rank_offset(m));
    }
    s.Flush();
  }
  const float eps = 1e-2f;
  for (size_t i = 0; i < g.params().size(); ++i) {
    const float v = g.params()[i];
    g.params()[i] = v + eps;
    const double lp = loss(g);
    g.params()[i] = v - eps;
    const double lm = loss(g);
    g.params()[i] = v;
    const double fd = (lp - lm) / (2 * eps);
    ASSERT_NEAR(g.grads()[i], fd, 2e-4 + 1e-3 * std::fabs(fd)) << "entry " << i;
  }
}

TEST(VmGridTest, ScatterMatchesFiniteDifferences) { CheckScatterAgainstFd(1); }
TEST(VmGridTest, ScatterOverThreadsMatchesFiniteDifferences) { CheckScatterAgainstFd(2); }

TEST(VmGridTest, ScatterCacheAlongMonotoneRayEqualsDirectSum) {
  // Many samples along a line through a larger grid (the production access pattern).
  VmGrid g = MakeGrid({20, 24, 18}, {4, 4, 4}, 2);
  VmGrid ref = g;
  std::vector<float> gprod(g.total_rank(), 0.f);
  ModeGradScatter s[3];
  for (int m = 0; m < 3; ++m) s[m].Bind(&g, m);
  std::vector<std::array<float, 3>> pts;
  for (int i = 0; i < 300; ++i) {
    const float t = -1.f + 2.f * i / 299.f;
    pts.push_back({0.9f * t, -0.7f * t + 0.1f, 0.3f * t - 0.2f});
  }
  for (size_t k = 0; k < pts.size(); ++k) {
    GridPoint gp;
    LocateGridPoint(pts[k].data(), g.res(), &gp);
    for (int r = 0; r < g.total_rank(); ++r) gprod[r] = std::sin(0.1f * (k + r));
    for (int m = 0; m < 3; ++m) {
      s[m].AddDensity(gp, std::cos(0.05f * k));
      s[m].AddProducts(gp, gprod.data() + g.rank_offset(m));
    }
  }
  for (int m = 0; m < 3; ++m) s[m].Flush();
  // Direct (uncached) accumulation in double.
  std::vector<double> direct(ref.params().size(), 0.0);
  for (size_t k = 0; k < pts.size(); ++k) {
    GridPoint gp;
    LocateGridPoint(pts[k].data(), ref.res(), &gp);
    for (int m = 0; m < 3; ++m) {
      const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m], R = ref.ranks()[m];
      for (int r = 0; r < R; ++r) {
        const double gr = std::cos(0.05f * k) + std::sin(0.1f * (k + ref.rank_offset(m) + r));
        double p = 0, l = 0;
        for (int c = 0; c < 4; ++c) {
          const int x = gp.i0[u] + (c & 1), y = gp.i0[v] + (c >> 1);
          const double wc = ((c & 1) ? gp.f[u] : 1 - gp.f[u]) * ((c >> 1) ? gp.f[v] : 1 - gp.f[v]);
          p += wc * ref.PlaneAt(m, y, x, r);
        }
        for (int c = 0; c < 2; ++c)
          l += (c ? gp.f[w] : 1 - gp.f[w]) * ref.LineAt(m, gp.i0[w] + c, r);
        for (int c = 0; c < 4; ++c) {
          const int x = gp.i0[u] + (c & 1), y = gp.i0[v] + (c >> 1);
          const double wc = ((c & 1) ? gp.f[u] : 1 - gp.f[u]) * ((c >> 1) ? gp.f[v] : 1 - gp.f[v]);
          direct[ref.plane_offset(m) + (static_cast<size_t>(y) * ref.res()[u] + x) * R + r] +=
              gr * wc * l;
        }
        for (int c = 0; c < 2; ++c)
          direct[ref.line_offset(m) + static_cast<size_t>(gp.i0[w] + c) * R + r] +=
              gr * (c ? gp.f[w] : 1 - gp.f[w]) * p;
      }
    }
  }
  for (size_t i = 0; i < direct.size(); ++i)
    ASSERT_NEAR(g.grads()[i], direct[i], 1e-4 + 1e-4 * std::fabs(direct[i])) << i;
}

TEST(VmGridTest, UpsampleOfLinearFunctionIsExact) {
  VmGrid g;
  g.Allocate({5, 4, 6}, {2, 1, 3});
  // Entries linear in the normalized vertex coordinates -> the bilinear / linear interpolant is
  // the same linear function at every resolution.
  auto coord = [](int i, int n) { return -1.0 + 2.0 * i / (n - 1); };
  auto fill = [&](VmGrid& grid) {
    for (int m = 0; m < 3; ++m) {
      const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
      for (int y = 0; y < grid.res()[v]; ++y)
        for (int x = 0; x < grid.res()[u]; ++x)
          for (int r = 0; r < grid.ranks()[m]; ++r)
            grid.PlaneAt(m, y, x, r) =
                static_cast<float>(0.3 * (r + 1) + 0.7 * coord(x, grid.res()[u]) -
                                   0.4 * (m + 1) * coord(y, grid.res()[v]));
      for (int i = 0; i < grid.res()[w]; ++i)
        for (int r = 0; r < grid.ranks()[m]; ++r)
          grid.LineAt(m, i, r) = static_cast<float>(0.5 - 0.25 * r + 0.6 * coord(i, grid.res()[w]));
    }
  };
  fill(g);
  VmGrid up = g;
  up.UpsampleTo({9, 13, 7});
  VmGrid expect;
  expect.Allocate({9, 13, 7}, {2, 1, 3});
  fill(expect);
  ASSERT_EQ(up.params().size(), expect.params().size());
  for (size_t i = 0; i < up.params().size(); ++i)
    ASSERT_NEAR(up.params()[i], expect.params()[i], 2e-6) << i;
  // Products (plane * line, bilinear in the coordinates) agree at any point.
  for (const auto& p : RandomPoints(50, 8)) {
    GridPoint a, b;
    LocateGridPoint(p.data(), g.res(), &a);
    LocateGridPoint(p.data(), up.res(), &b);
    std::vector<float> pa(g.total_rank()), pb(g.total_rank());
    g.Products(a, pa.data());
    up.Products(b, pb.data());
    for (int r = 0; r < g.total_rank(); ++r) EXPECT_NEAR(pa[r], pb[r], 1e-5);
  }
}

TEST(VmGridTest, UpsampleKeepsVertexValuesWhenDoublingMinusOne) {
  // new = 2*(n-1)+1: the old vertices are a subset of the new ones.
  VmGrid g = MakeGrid({4, 5, 6}, {3, 3, 3}, 4);
  VmGrid up = g;
  up.UpsampleTo({7, 9, 11});
  for (int m = 0; m < 3; ++m) {
    const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
    for (int y = 0; y < g.res()[v]; ++y)
      for (int x = 0; x < g.res()[u]; ++x)
        for (int r = 0; r < 3; ++r)
          EXPECT_NEAR(up.PlaneAt(m, 2 * y, 2 * x, r), g.PlaneAt(m, y, x, r), 1e-6);
    for (int i = 0; i < g.res()[w]; ++i)
      for (int r = 0; r < 3; ++r) EXPECT_NEAR(up.LineAt(m, 2 * i, r), g.LineAt(m, i, r), 1e-6);
  }
}

TEST(VmGridTest, CropKeepsSubGrid) {
  VmGrid g = MakeGrid({8, 9, 10}, {2, 2, 2}, 6);
  VmGrid c = g;
  c.Crop({1, 2, 3}, {7, 9, 6});
  EXPECT_EQ(c.res(), (std::array<int, 3>{6, 7, 3}));
  for (int m = 0; m < 3; ++m) {
    const int u = kMatMode[m][0], v = kMatMode[m][1], w = kVecMode[m];
    const std::array<int, 3> lo{1, 2, 3};
    for (int y = 0; y < c.res()[v]; ++y)
      for (int x = 0; x < c.res()[u]; ++x)
        for (int r = 0; r < 2; ++r)
          EXPECT_EQ(c.PlaneAt(m, y, x, r), g.PlaneAt(m, y + lo[v], x + lo[u], r));
    for (int i = 0; i < c.res()[w]; ++i)
      for (int r = 0; r < 2; ++r) EXPECT_EQ(c.LineAt(m, i, r), g.LineAt(m, i + lo[w], r));
  }
  EXPECT_THROW(c.Crop({0, 0, 0}, {7, 7, 4}), std::runtime_error);
}

TEST(VmGridTest, L1ValueAndGradient) {
  VmGrid g = MakeGrid({4, 5, 3}, {2, 3, 2}, 12);
  g.params()[3] = 0.f;  // sign(0) = 0
  double expect = 0;
  for (int t = 0; t < 6; ++t) {
    const size_t off = t < 3 ? g.plane_offset(t) : g.line_offset(t - 3);
    const size_t n = t < 3 ? g.plane_size(t) : g.line_size(t - 3);
    double s = 0;
    for (size_t k = 0; k < n; ++k) s += std::fabs(g.params()[off + k]);
    expect += s / n;
  }
  g.ZeroGrads();
  const float weight = 0.5f;
  const double value = g.L1(weight);
  EXPECT_NEAR(value, expect, 1e-6);
  const float eps = 1e-3f;
  for (size_t i = 0; i < g.params().size(); ++i) {
    const float v = g.params()[i];
    if (v == 0.f) {
      EXPECT_EQ(g.grads()[i], 0.f);
      continue;
    }
    VmGrid tmp = g;
    tmp.params()[i] = v + eps;
    const double lp = tmp.L1(0.f);
    tmp.params()[i] = v - eps;
    const double lm = tmp.L1(0.f);
    EXPECT_NEAR(g.grads()[i], weight * (lp - lm) / (2 * eps), 1e-4) << i;
  }
}

// TensoRF's TVLoss on the [1, C, H, W] plane, straight from its definition, times 1e-2 per plane.
double ReferencePlaneTv(const VmGrid& g) {
  double total = 0;
  for (int m = 0; m < 3; ++m) {
    const int W = g.res()[kMatMode[m][0]], H = g.res()[kMatMode[m][1]], C = g.ranks()[m];
    auto at = [&](int y, int x, int c) {
      return static_cast<double>(g.plane(m)[(static_cast<size_t>(y) * W + x) * C + c]);
    };
    double h_tv = 0, w_tv = 0;
    for (int c = 0; c < C; ++c) {
      for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
          if (y + 1 < H) h_tv += std::pow(at(y + 1, x, c) - at(y, x, c), 2);
          if (x + 1 < W) w_tv += std::pow(at(y, x + 1, c) - at(y, x, c), 2);
        }
      }
    }
    const double count_h = double(C) * (H - 1) * W, count_w = double(C) * H * (W - 1);
    total += 1e-2 * 2 * (h_tv / count_h + w_tv / count_w);
  }
  return total;
}

TEST(VmGridTest, PlaneTotalVariationValueAndGradient) {
  VmGrid g = MakeGrid({4, 5, 3}, {2, 3, 2}, 21);
  g.ZeroGrads();
  const float weight = 3.f;
  const double value = g.PlaneTotalVariation(weight);
  EXPECT_GT(value, 1e-4);
  EXPECT_NEAR(value, ReferencePlaneTv(g), 1e-7 * value);
  const float eps = 1e-2f;  // the loss is quadratic: central differences are exact but rounding
  int nonzero = 0;
  for (size_t i = 0; i < g.params().size(); ++i) {
    VmGrid tmp = g;
    const float v = g.params()[i];
    tmp.params()[i] = v + eps;
    const double lp = ReferencePlaneTv(tmp);
    tmp.params()[i] = v - eps;
    const double lm = ReferencePlaneTv(tmp);
    const double fd = weight * (lp - lm) / (2 * eps);
    EXPECT_NEAR(g.grads()[i], fd, 1e-6 + 1e-4 * std::fabs(fd)) << i;
    nonzero += g.grads()[i] != 0.f;
  }
  // Every plane entry has a neighbour; the lines are not regularised.
  size_t plane_entries = 0;
  for (int m = 0; m < 3; ++m) plane_entries += g.plane_size(m);
  EXPECT_EQ(nonzero, static_cast<int>(plane_entries));
  for (int m = 0; m < 3; ++m) {
    for (size_t k = 0; k < g.line_size(m); ++k) EXPECT_EQ(g.line_grad(m)[k], 0.f);
  }
  // A constant plane has no variation.
  VmGrid flat = g;
  for (float& v : flat.params()) v = 0.25f;
  flat.ZeroGrads();
  EXPECT_EQ(flat.PlaneTotalVariation(1.f), 0.0);
  for (float v : flat.grads()) EXPECT_EQ(v, 0.f);
}

TEST(VmGridTest, PlaneTotalVariationSameForAnyThreadCount) {
  VmGrid a = MakeGrid({90, 80, 70}, {4, 4, 4}, 5);  // planes above the parallel threshold
  VmGrid b = a;
  a.ZeroGrads();
  b.ZeroGrads();
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const double va = a.PlaneTotalVariation(0.7f);
  omp_set_num_threads(3);
  const double vb = b.PlaneTotalVariation(0.7f);
  omp_set_num_threads(threads);
  EXPECT_NEAR(va, vb, 1e-12 * va);
  EXPECT_EQ(a.grads(), b.grads());
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
