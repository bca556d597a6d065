// Block DCT of the feature grids (encoder/grid_dct.h) and the rate objective built on it
// (trainer/rate/rate_objective.h).
#include "encoder/grid_dct.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <numeric>
#include <random>
#include <vector>

#include "encoder/coef_quantizer.h"
#include "format/coefficients/float_dct.h"
#include "trainer/rate/entropy_model.h"
#include "trainer/rate/rate_objective.h"

namespace ecrf {
namespace trainer {
namespace {

std::vector<float> RandomVector(size_t n, uint32_t seed, float scale = 1.f) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> nd(0.f, scale);
  std::vector<float> v(n);
  for (float& x : v) x = nd(rng);
  return v;
}

double MaxAbsDifference(const std::vector<float>& a, const std::vector<float>& b) {
  double m = 0.0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(double(a[i]) - b[i]));
  return m;
}

double Dot(const std::vector<float>& a, const std::vector<float>& b) {
  double s = 0.0;
  for (size_t i = 0; i < a.size(); ++i) s += double(a[i]) * b[i];
  return s;
}

struct LayoutCase {
  bool plane;
  std::array<int, 3> res;
  int rank;
  int m;
  int block[3];
};

std::vector<LayoutCase> Cases() {
  return {
      {true, {19, 13, 7}, 5, 0, {4, 8, 8}},     // every axis padded
      {true, {19, 13, 7}, 5, 1, {16, 16, 16}},  // one block per axis, heavy padding
      {true, {16, 32, 8}, 16, 2, {16, 8, 8}},   // exact multiples
      {true, {9, 11, 6}, 3, 1, {1, 4, 4}},      // 1 x K x K plane blocks
      {true, {5, 5, 5}, 48, 0, {32, 2, 1}},     {false, {19, 13, 7}, 5, 0, {1, 8, 8}},
      {false, {19, 13, 10}, 12, 2, {1, 4, 32}},
  };
}

encoder::GridBlockLayout MakeCaseLayout(const LayoutCase& c) {
  return c.plane ? encoder::PlaneBlockLayout(c.res, c.rank, c.m, c.block)
                 : encoder::LineBlockLayout(c.res, c.rank, c.m, c.block);
}

TEST(GridDctTest, LayoutCountsAndPaddedExtent) {
  const int block[3] = {16, 16, 16};
  const encoder::GridBlockLayout L = encoder::PlaneBlockLayout({300, 300, 300}, 48, 0, block);
  EXPECT_EQ(L.extent[0], 48);
  EXPECT_EQ(L.blocks[0], 3);
  EXPECT_EQ(L.blocks[1], 19);
  EXPECT_EQ(L.blocks[2], 19);
  EXPECT_EQ(L.padded[1], 304);
  EXPECT_EQ(L.num_blocks(), 3 * 19 * 19);
  EXPECT_EQ(L.tensor_size(), 300u * 300u * 48u);
  const int lb[3] = {1, 8, 8};
  const encoder::GridBlockLayout LL =
      encoder::LineBlockLayout({300, 200, 100}, 48, 0, lb);  // w = axis 2
  EXPECT_EQ(LL.extent[2], 100);
  EXPECT_EQ(LL.blocks[1], 6);
  EXPECT_EQ(LL.blocks[2], 13);
  const int bad[3] = {3, 8, 8};
  EXPECT_THROW(encoder::PlaneBlockLayout({8, 8, 8}, 4, 0, bad), std::invalid_argument);
  const int big[3] = {32, 32, 32};
  EXPECT_THROW(encoder::PlaneBlockLayout({8, 8, 8}, 4, 0, big), std::invalid_argument);
  EXPECT_THROW(encoder::LineBlockLayout({8, 8, 8}, 4, 0, block), std::invalid_argument);
}

// ForwardBlocks equals format/float_dct's double DCT of the edge-replicated block.
TEST(GridDctTest, MatchesReferenceDctOfEdgePaddedBlocks) {
  for (const LayoutCase& c : Cases()) {
    const encoder::GridBlockLayout L = MakeCaseLayout(c);
    const std::vector<float> t = RandomVector(L.tensor_size(), 7);
    std::vector<float> coeffs(L.num_coeffs());
    encoder::ForwardBlocks(t.data(), L, coeffs.data());
    const int V = L.block_volume();
    double max_err = 0.0;
    for (int id = 0; id < L.num_blocks(); ++id) {
      const int b2 = id % L.blocks[2], b1 = (id / L.blocks[2]) % L.blocks[1],
                b0 = id / (L.blocks[1] * L.blocks[2]);
      std::vector<double> blk(V);
      for (int i0 = 0; i0 < L.block[0]; ++i0) {
        for (int i1 = 0; i1 < L.block[1]; ++i1) {
          for (int i2 = 0; i2 < L.block[2]; ++i2) {
            const int e0 = std::min(b0 * L.block[0] + i0, L.extent[0] - 1);
            const int e1 = std::min(b1 * L.block[1] + i1, L.extent[1] - 1);
            const int e2 = std::min(b2 * L.block[2] + i2, L.extent[2] - 1);
            blk[(i0 * L.block[1] + i1) * L.block[2] + i2] =
                t[e0 * L.stride[0] + e1 * L.stride[1] + e2 * L.stride[2]];
          }
        }
      }
      ForwardDct(blk.data(), L.block);
      for (int p = 0; p < V; ++p) {
        max_err = std::max(max_err, std::abs(blk[p] - coeffs[static_cast<size_t>(id) * V + p]));
      }
    }
    EXPECT_LT(max_err, 2e-5) << "case block " << c.block[0] << "x" << c.block[1] << "x"
                             << c.block[2];
  }
}

// <F(pad(x)), y> == <x, pad^T(F^T(y))> for random x, y.
TEST(GridDctTest, BackwardIsAdjointOfForwardWithPadding) {
  for (const LayoutCase& c : Cases()) {
    const encoder::GridBlockLayout L = MakeCaseLayout(c);
    const std::vector<float> x = RandomVector(L.tensor_size(), 11);
    const std::vector<float> y = RandomVector(L.num_coeffs(), 12);
    std::vector<float> fx(L.num_coeffs());
    encoder::ForwardBlocks(x.data(), L, fx.data());
    std::vector<float> fty(L.tensor_size(), 0.5f);  // accumulates onto existing values
    encoder::BackwardBlocks(y.data(), L, fty.data());
    for (float& v : fty) v -= 0.5f;
    const double lhs = Dot(fx, y), rhs = Dot(x, fty);
    EXPECT_NEAR(lhs, rhs, 1e-5 * (std::abs(lhs) + std::sqrt(double(L.num_coeffs()))));
  }
}

TEST(GridDctTest, PaddedTensorRoundTripsAfterCropping) {
  for (const LayoutCase& c : Cases()) {
    const encoder::GridBlockLayout L = MakeCaseLayout(c);
    const std::vector<float> x = RandomVector(L.tensor_size(), 13, 3.f);
    std::vector<float> coeffs(L.num_coeffs());
    encoder::ForwardBlocks(x.data(), L, coeffs.data());
    std::vector<float> back(L.tensor_size(), 1e9f);
    encoder::InverseBlocks(coeffs.data(), L, back.data());
    for (size_t i = 0; i < x.size(); ++i) ASSERT_NEAR(back[i], x[i], 1e-5f) << i;
  }
}

// The fused block-by-block version gives the bits of its three steps, on every layout (the
// padded ones included), at a fine step, a coarse one and with a dead zone.
TEST(GridDctTest, QuantizeBlocksEqualsForwardQuantizeInverse) {
  for (const LayoutCase& c : Cases()) {
    const encoder::GridBlockLayout L = MakeCaseLayout(c);
    const std::vector<float> x = RandomVector(L.tensor_size(), 21, 2.f);
    for (const auto& [step, offset] :
         {std::pair<double, double>{0.01, 0.5}, {0.7, 0.5}, {0.05, 0.3}}) {
      std::vector<float> coeffs(L.num_coeffs());
      encoder::ForwardBlocks(x.data(), L, coeffs.data());
      for (float& v : coeffs)
        v = static_cast<float>(encoder::QuantizeLevel(double(v), step, offset) * step);
      std::vector<float> expected(L.tensor_size(), 1e9f), fused(L.tensor_size(), -1e9f);
      encoder::InverseBlocks(coeffs.data(), L, expected.data());
      encoder::QuantizeBlocks(x.data(), L, step, offset, fused.data());
      ASSERT_EQ(0, std::memcmp(expected.data(), fused.data(), fused.size() * sizeof(float)))
          << "block " << c.block[0] << "x" << c.block[1] << "x" << c.block[2] << " step " << step;
      // A coarse step moves the values; a round trip that did nothing would pass the memcmp.
      if (step == 0.7) EXPECT_GT(MaxAbsDifference(fused, x), 0.05);
    }
  }
}

TEST(GridDctTest, EdgeReplicationKeepsConstantTensorsDcOnly) {
  // A constant tensor padded by replication stays constant: every block has only a DC term.
  const int block[3] = {16, 16, 16};
  const encoder::GridBlockLayout L = encoder::PlaneBlockLayout({21, 10, 4}, 7, 0, block);
  std::vector<float> x(L.tensor_size(), 2.f);
  std::vector<float> coeffs(L.num_coeffs());
  encoder::ForwardBlocks(x.data(), L, coeffs.data());
  for (int id = 0; id < L.num_blocks(); ++id) {
    EXPECT_NEAR(coeffs[static_cast<size_t>(id) * 4096], 2.f * 64.f, 1e-3f);
    for (int p = 1; p < 4096; ++p)
      ASSERT_NEAR(coeffs[static_cast<size_t>(id) * 4096 + p], 0.f, 1e-4f);
  }
}

TEST(GridDctTest, BlockListMatchesFullTransform) {
  const int block[3] = {4, 8, 8};
  const encoder::GridBlockLayout L = encoder::PlaneBlockLayout({19, 13, 7}, 9, 0, block);
  const int V = L.block_volume();
  const std::vector<float> x = RandomVector(L.tensor_size(), 17);
  std::vector<float> full(L.num_coeffs());
  encoder::ForwardBlocks(x.data(), L, full.data());
  const std::vector<int> ids = {L.num_blocks() - 1, 0, 3, 5};
  std::vector<float> sub(ids.size() * V);
  encoder::ForwardBlockList(x.data(), L, ids.data(), static_cast<int>(ids.size()), sub.data());
  for (size_t j = 0; j < ids.size(); ++j) {
    for (int p = 0; p < V; ++p)
      ASSERT_EQ(sub[j * V + p], full[static_cast<size_t>(ids[j]) * V + p]);
  }
  // Backward of a list == backward of the full array with zeros elsewhere.
  const std::vector<float> g = RandomVector(sub.size(), 18);
  std::vector<float> gfull(L.num_coeffs(), 0.f);
  for (size_t j = 0; j < ids.size(); ++j) {
    std::copy(g.begin() + j * V, g.begin() + (j + 1) * V,
              gfull.begin() + static_cast<size_t>(ids[j]) * V);
  }
  std::vector<float> a(L.tensor_size(), 0.f), b(L.tensor_size(), 0.f);
  encoder::BackwardBlockList(g.data(), L, ids.data(), static_cast<int>(ids.size()), a.data());
  encoder::BackwardBlocks(gfull.data(), L, b.data());
  for (size_t i = 0; i < a.size(); ++i) ASSERT_NEAR(a[i], b[i], 1e-6f);
  const int bad = L.num_blocks();
  EXPECT_THROW(encoder::ForwardBlockList(x.data(), L, &bad, 1, sub.data()), std::invalid_argument);
}

// Full appearance grid at 300^3 (3 planes 300x300x48 + 3 lines 300x48): forward + backward.
TEST(GridDctTest, SpeedFullAppearanceGrid300) {
  VmGrid grid;
  grid.Allocate({300, 300, 300}, {48, 48, 48});
  grid.InitNormal(0.1f, 1);
  const encoder::RateConfig config;
  std::vector<encoder::GridBlockLayout> layouts;
  size_t total = 0;
  for (int t = 0; t < 6; ++t) {
    layouts.push_back(RateTensorLayout(grid, t, config));
    total += layouts.back().num_coeffs();
  }
  std::vector<float> coeffs(total);
  double best_f = 1e9, best_b = 1e9, cpu = 1e9;
  for (int rep = 0; rep < 3; ++rep) {
    const std::clock_t c0 = std::clock();
    auto t0 = std::chrono::steady_clock::now();
    size_t off = 0;
    for (int t = 0; t < 6; ++t) {
      encoder::ForwardBlocks(RateTensorData(grid, t), layouts[t], coeffs.data() + off);
      off += layouts[t].num_coeffs();
    }
    auto t1 = std::chrono::steady_clock::now();
    off = 0;
    for (int t = 0; t < 6; ++t) {
      encoder::BackwardBlocks(coeffs.data() + off, layouts[t], RateTensorGrad(grid, t));
      off += layouts[t].num_coeffs();
    }
    auto t2 = std::chrono::steady_clock::now();
    best_f = std::min(best_f, std::chrono::duration<double>(t1 - t0).count());
    best_b = std::min(best_b, std::chrono::duration<double>(t2 - t1).count());
    cpu = std::min(cpu, double(std::clock() - c0) / CLOCKS_PER_SEC);
  }
  std::printf(
      "[speed] app grid 300^3: %zu values, %zu coeffs; forward %.1f ms, backward %.1f ms "
      "wall; forward+backward %.1f ms CPU\n",
      grid.params().size(), total, best_f * 1e3, best_b * 1e3, cpu * 1e3);
  // After 3 accumulations of F^T F x: grads = 3 * pad^T pad x; interior elements = 3 x.
  EXPECT_NEAR(grid.grads()[12345], 3.f * grid.params()[12345], 1e-4f);
}

// ---------------------------------------------------------------------------------------------
// Rate objective.

struct SmallSetup {
  VmGrid density, app;
  encoder::RateConfig config;
  std::vector<float> steps;
  FactorizedEntropyModel model;
  SmallSetup() {
    density.Allocate({10, 12, 9}, {4, 5, 3});
    density.InitNormal(0.5f, 3);
    app.Allocate({10, 12, 9}, {6, 5, 7});
    app.InitNormal(0.3f, 4);
    config.plane_block[0] = 4;
    config.plane_block[1] = 4;
    config.plane_block[2] = 4;
    config.line_block[1] = 4;
    config.line_block[2] = 4;
    for (int i = 0; i < 12; ++i) steps.push_back(0.05f + 0.01f * i);
    model.Init(NumRateModels(2), 5);
  }
  std::vector<VmGrid*> grids() { return {&density, &app}; }
};

TEST(RateObjectiveTest, FrequencyBands) {
  EXPECT_EQ(FrequencyOctave(0), 0);
  EXPECT_EQ(FrequencyOctave(1), 1);
  EXPECT_EQ(FrequencyOctave(2), 2);
  EXPECT_EQ(FrequencyOctave(3), 2);
  EXPECT_EQ(FrequencyOctave(4), 3);
  EXPECT_EQ(FrequencyOctave(15), 4);
  EXPECT_EQ(FrequencyOctave(16), 5);
  EXPECT_EQ(FrequencyOctave(62), 5);
  EXPECT_EQ(FrequencyBand(false, 0, 0, 0), 0);
  EXPECT_EQ(FrequencyBand(false, 0, 1, 0), 1);
  EXPECT_EQ(FrequencyBand(false, 1, 1, 0), 6 + 1);
  EXPECT_EQ(FrequencyBand(false, 3, 2, 1), 12 + 2);
  EXPECT_EQ(FrequencyBand(false, 15, 15, 15), 24 + 5);
  EXPECT_EQ(FrequencyBand(false, 31, 0, 0), 30);
  EXPECT_EQ(FrequencyBand(true, 0, 5, 0), 18);  // line: k1 = channel, k2 = position
  EXPECT_EQ(FrequencyBand(true, 0, 0, 7), 3);
  int max_band = 0;
  for (int a = 0; a < 32; ++a) {
    for (int b = 0; b < 32; ++b) max_band = std::max(max_band, FrequencyBand(false, a, b, 31));
  }
  EXPECT_EQ(max_band, kNumFrequencyBands - 1);
}

TEST(RateObjectiveTest, RegularizerValueAndGradient) {
  SmallSetup s;
  s.density.ZeroGrads();
  s.app.ZeroGrads();
  const RateEstimate e = AddRateGradients(s.grids(), s.steps, s.config, &s.model, 0.f, 1.f, 1.f, 1);
  // Value: sum of squares of the padded blocks' coefficients == of the padded tensors.
  double reg = 0.0;
  for (VmGrid* g : s.grids()) {
    for (int t = 0; t < 6; ++t) {
      const encoder::GridBlockLayout L = RateTensorLayout(*g, t, s.config);
      std::vector<float> c(L.num_coeffs());
      encoder::ForwardBlocks(RateTensorData(*g, t), L, c.data());
      reg += Dot(c, c);
    }
  }
  EXPECT_NEAR(e.regularizer, reg, 1e-5 * reg);
  // Gradient by central differences (exact for a quadratic up to float rounding), including
  // corner / edge elements that padding replicates.
  for (VmGrid* g : s.grids()) {
    const std::vector<size_t> probe = {0,
                                       7,
                                       g->params().size() / 2,
                                       g->params().size() - 1,
                                       g->line_offset(0) - 1,
                                       g->line_offset(2) + 3};
    for (size_t i : probe) {
      const float h = 1e-2f;
      const float orig = g->params()[i];
      auto value = [&](float v) {
        g->params()[i] = v;
        FactorizedEntropyModel m2 = s.model;
        VmGrid d2 = s.density, a2 = s.app;
        return AddRateGradients({&d2, &a2}, s.steps, s.config, &m2, 0.f, 1.f, 1.f, 1).regularizer;
      };
      const double fd = (value(orig + h) - value(orig - h)) / (2.0 * h);
      g->params()[i] = orig;
      EXPECT_NEAR(g->grads()[i], fd, 2e-3 * (1.0 + std::abs(fd))) << "element " << i;
    }
  }
}

// Noise is a function of (seed, tensor, block, position), so the noisy bits are a differentiable
// function of the grid for a fixed seed: finite differences of the estimate match its gradient.
// Steps are large enough that no likelihood hits the lower bound (where CompressAI's bound passes
// a gradient that the constant value does not have).
TEST(RateObjectiveTest, BitsGradientMatchesFiniteDifferences) {
  SmallSetup s;
  for (int i = 0; i < 12; ++i) s.steps[i] = 0.3f + 0.05f * i;
  s.density.ZeroGrads();
  s.app.ZeroGrads();
  const float lambda_e = 1.f, lambda_r = 0.3f;
  AddRateGradients(s.grids(), s.steps, s.config, &s.model, lambda_e, lambda_r, 1.f, 9);
  auto loss = [&]() {
    FactorizedEntropyModel m2 = s.model;
    VmGrid d2 = s.density, a2 = s.app;
    const RateEstimate e = AddRateGradients({&d2, &a2}, s.steps, s.config, &m2, 0.f, 0.f, 1.f, 9);
    return lambda_e * e.bits + lambda_r * e.regularizer;
  };
  int checked = 0;
  for (VmGrid* g : s.grids()) {
    for (size_t i : {size_t(1), size_t(50), g->params().size() / 3, g->params().size() - 2,
                     g->line_offset(1) + 1}) {
      const float h =
          1e-2f;  // float rounding of ~10^4 per-coefficient bit counts needs a wide step
      const float orig = g->params()[i];
      g->params()[i] = orig + h;
      const double up = loss();
      g->params()[i] = orig - h;
      const double dn = loss();
      g->params()[i] = orig;
      const double fd = (up - dn) / (2.0 * h);
      EXPECT_NEAR(g->grads()[i], fd, 2e-2 * (1.0 + std::abs(fd))) << "element " << i;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 10);
}

TEST(RateObjectiveTest, StochasticEstimateIsUnbiased) {
  SmallSetup s;
  s.config.line_block[1] = 2;  // more line blocks
  double full_bits = 0.0, full_reg = 0.0;
  const int full_reps = 10;
  for (int seed = 0; seed < full_reps; ++seed) {
    const RateEstimate e =
        AddRateGradients(s.grids(), s.steps, s.config, &s.model, 0.f, 0.f, 1.f, 1000 + seed);
    full_bits += e.bits / full_reps;
    full_reg += e.regularizer / full_reps;
  }
  for (float f : {0.25f, 0.1f}) {
    double bits = 0.0, reg = 0.0;
    const int reps = 400;
    for (int seed = 0; seed < reps; ++seed) {
      const RateEstimate e =
          AddRateGradients(s.grids(), s.steps, s.config, &s.model, 0.f, 0.f, f, seed);
      bits += e.bits / reps;
      reg += e.regularizer / reps;
    }
    EXPECT_NEAR(bits, full_bits, 0.03 * full_bits) << "fraction " << f;
    EXPECT_NEAR(reg, full_reg, 0.03 * full_reg) << "fraction " << f;
  }
}

TEST(RateObjectiveTest, EvaluateRateMatchesPerCoefficientModel) {
  SmallSetup s;
  const RateReport rep = EvaluateRate({&s.density, &s.app}, s.steps, s.config, s.model);
  ASSERT_EQ(rep.bits.size(), 12u);
  double total = 0.0;
  for (int ti : {0, 4, 9}) {
    const VmGrid& g = ti < 6 ? s.density : s.app;
    const encoder::GridBlockLayout L = RateTensorLayout(g, ti % 6, s.config);
    std::vector<float> c(L.num_coeffs());
    encoder::ForwardBlocks(RateTensorData(g, ti % 6), L, c.data());
    double bits = 0.0;
    for (size_t i = 0; i < c.size(); ++i) {
      const int p = static_cast<int>(i % L.block_volume());
      const int k2 = p % L.block[2], k1 = (p / L.block[2]) % L.block[1],
                k0 = p / (L.block[1] * L.block[2]);
      const int model = RateModelIndex(ti, FrequencyBand(ti % 6 >= 3, k0, k1, k2));
      bits += s.model.BitsDouble(model, std::round(c[i] / s.steps[ti]), nullptr, nullptr);
    }
    EXPECT_NEAR(rep.bits[ti], bits, 1e-4 * bits) << "tensor " << ti;
    EXPECT_EQ(rep.coeffs[ti], c.size());
  }
  for (double b : rep.bits) total += b;
  EXPECT_NEAR(rep.total_bits, total, 1e-9 * total);
}

// Density (ranks 16) + appearance (ranks 48) grids at 300^3: cost of one rate step.
TEST(RateObjectiveTest, SpeedAt300) {
  VmGrid density, app;
  density.Allocate({300, 300, 300}, {16, 16, 16});
  density.InitNormal(0.1f, 1);
  app.Allocate({300, 300, 300}, {48, 48, 48});
  app.InitNormal(0.1f, 2);
  const encoder::RateConfig config;
  std::vector<float> steps(12, 0.02f);
  FactorizedEntropyModel model;
  model.Init(NumRateModels(2), 3);
  for (float f : {1.f, 0.1f, 0.02f}) {
    double best = 1e9, cpu = 1e9;
    for (int rep = 0; rep < 2; ++rep) {
      const std::clock_t c0 = std::clock();
      auto t0 = std::chrono::steady_clock::now();
      AddRateGradients({&density, &app}, steps, config, &model, 1e-9f, 1e-9f, f, rep);
      best = std::min(best,
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      cpu = std::min(cpu, double(std::clock() - c0) / CLOCKS_PER_SEC);
    }
    std::printf(
        "[speed] AddRateGradients 300^3 density+app, fraction %.2f: %.1f ms wall, %.1f ms "
        "CPU\n",
        f, best * 1e3, cpu * 1e3);
  }
  auto t0 = std::chrono::steady_clock::now();
  const RateReport rep = EvaluateRate({&density, &app}, steps, config, model);
  std::printf("[speed] EvaluateRate 300^3 density+app: %.1f ms (%.0f bits)\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * 1e3,
              rep.total_bits);
  EXPECT_GT(rep.total_bits, 0.0);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
