#include "trainer/train/adam.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace ecrf {
namespace trainer {
namespace {

// torch.optim.Adam (no weight decay, no amsgrad), computed by hand in double.
struct DoubleAdam {
  double beta1, beta2, eps;
  std::vector<double> m, v;
  long t = 0;
  DoubleAdam(size_t n, const AdamConfig& c)
      : beta1(c.beta1), beta2(c.beta2), eps(c.epsilon), m(n, 0.0), v(n, 0.0) {}
  void Step(std::vector<double>* p, const std::vector<double>& g, double lr) {
    ++t;
    for (size_t i = 0; i < p->size(); ++i) {
      m[i] = beta1 * m[i] + (1 - beta1) * g[i];
      v[i] = beta2 * v[i] + (1 - beta2) * g[i] * g[i];
      const double denom = std::sqrt(v[i]) / std::sqrt(1 - std::pow(beta2, t)) + eps;
      (*p)[i] -= lr / (1 - std::pow(beta1, t)) * m[i] / denom;
    }
  }
};

TEST(AdamTest, FirstStepByHand) {
  // Step 1: m = 0.1 g, v = 0.01 g^2, mhat = g, vhat = g^2 -> p -= lr * g / (|g| + eps).
  Adam adam(3, AdamConfig{});
  std::vector<float> p = {1.0f, -2.0f, 0.5f};
  const std::vector<float> g = {0.5f, -4.0f, 0.0f};
  adam.Step(p.data(), g.data(), 3, 0.1f);
  EXPECT_EQ(adam.step_count(), 1);
  EXPECT_NEAR(p[0], 1.0 - 0.1 * 0.5 / (0.5 + 1e-8), 1e-7);
  EXPECT_NEAR(p[1], -2.0 + 0.1 * 4.0 / (4.0 + 1e-8), 1e-7);
  EXPECT_EQ(p[2], 0.5f);  // zero gradient, zero moment: no move
  // (1 - beta) of the float betas differs from 0.1 / 0.01 in the 7th digit.
  EXPECT_NEAR(adam.first_moment()[1], -0.4, 1e-6);
  EXPECT_NEAR(adam.second_moment()[1], 0.16, 1e-6);
}

TEST(AdamTest, MatchesTorchFormulaOverSeveralSteps) {
  AdamConfig cfg;  // betas (0.9, 0.99), eps 1e-8 as TensoRF
  const size_t n = 5;
  Adam adam(n, cfg);
  DoubleAdam ref(n, cfg);
  std::vector<float> p = {0.3f, -1.2f, 2.0f, 0.0f, 1e-3f};
  std::vector<double> pd(p.begin(), p.end());
  const float lrs[] = {0.02f, 0.02f, 0.015f, 0.01f, 0.001f, 0.05f};  // caller changes lr
  std::mt19937 rng(1);
  std::normal_distribution<float> normal;
  for (float lr : lrs) {
    std::vector<float> g(n);
    for (float& v : g) v = normal(rng);
    g[3] = 1e-6f * normal(rng);  // tiny gradients: eps matters
    adam.Step(p.data(), g.data(), n, lr);
    ref.Step(&pd, std::vector<double>(g.begin(), g.end()), lr);
    for (size_t i = 0; i < n; ++i) {
      ASSERT_NEAR(p[i], pd[i], 2e-6 * (1 + std::fabs(pd[i]))) << "step " << adam.step_count();
      ASSERT_NEAR(adam.first_moment()[i], ref.m[i], 1e-6 * (1 + std::fabs(ref.m[i])));
      ASSERT_NEAR(adam.second_moment()[i], ref.v[i], 1e-6 * (1 + std::fabs(ref.v[i])));
    }
  }
  EXPECT_EQ(adam.step_count(), 6);
}

TEST(AdamTest, LargeArrayParallelPathMatchesReference) {
  AdamConfig cfg;
  cfg.beta2 = 0.999f;
  const size_t n = 300001;  // several OpenMP blocks and a ragged tail
  Adam adam(n, cfg);
  DoubleAdam ref(n, cfg);
  std::vector<float> p(n);
  std::mt19937 rng(2);
  std::normal_distribution<float> normal;
  for (float& v : p) v = normal(rng);
  std::vector<double> pd(p.begin(), p.end());
  for (int step = 0; step < 3; ++step) {
    std::vector<float> g(n);
    for (float& v : g) v = normal(rng);
    adam.Step(p.data(), g.data(), n, 0.01f);
    ref.Step(&pd, std::vector<double>(g.begin(), g.end()), 0.01);
  }
  double max_err = 0.0;
  for (size_t i = 0; i < n; ++i) max_err = std::max(max_err, std::fabs(p[i] - pd[i]));
  EXPECT_LT(max_err, 1e-5);
}

TEST(AdamTest, ResetClearsState) {
  Adam adam(4, AdamConfig{});
  std::vector<float> p = {1, 2, 3, 4}, g = {1, -1, 2, -2};
  for (int i = 0; i < 3; ++i) adam.Step(p.data(), g.data(), 4, 0.1f);
  adam.Reset(6);
  EXPECT_EQ(adam.size(), 6u);
  EXPECT_EQ(adam.step_count(), 0);
  for (float v : adam.first_moment()) EXPECT_EQ(v, 0.0f);
  for (float v : adam.second_moment()) EXPECT_EQ(v, 0.0f);
  // After a reset the first step is again the bias-corrected sign step of size lr.
  std::vector<float> q(6, 0.0f), h = {3, -3, 0.25f, -0.25f, 100, -100};
  adam.Step(q.data(), h.data(), 6, 0.01f);
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(q[i], h[i] > 0 ? -0.01f : 0.01f, 1e-7f) << i;
  // Checkpoint round trip: restoring moments and step count continues identically.
  Adam restored(6, AdamConfig{});
  restored.first_moment() = adam.first_moment();
  restored.second_moment() = adam.second_moment();
  restored.set_step_count(adam.step_count());
  std::vector<float> q2 = q;
  adam.Step(q.data(), h.data(), 6, 0.01f);
  restored.Step(q2.data(), h.data(), 6, 0.01f);
  EXPECT_EQ(q, q2);
}

TEST(AdamTest, MinimizesQuadratic) {
  // f(p) = sum a_i (p_i - c_i)^2 with very different curvatures.
  const size_t n = 64;
  std::vector<float> a(n), c(n), p(n, 0.0f);
  for (size_t i = 0; i < n; ++i) {
    a[i] = std::pow(10.0f, static_cast<float>(i % 5) - 2.0f);
    c[i] = std::sin(static_cast<float>(i)) * 3.0f;
  }
  auto loss = [&]() {
    double l = 0.0;
    for (size_t i = 0; i < n; ++i) l += a[i] * (p[i] - c[i]) * (p[i] - c[i]);
    return l;
  };
  const double initial = loss();
  Adam adam(n, AdamConfig{});
  std::vector<float> g(n);
  for (int step = 0; step < 3000; ++step) {
    for (size_t i = 0; i < n; ++i) g[i] = 2.0f * a[i] * (p[i] - c[i]);
    const float lr = 0.1f * std::pow(0.01f, step / 3000.0f);  // exponential decay as TensoRF
    adam.Step(p.data(), g.data(), n, lr);
  }
  EXPECT_LT(loss(), initial * 1e-6);
  for (size_t i = 0; i < n; ++i) EXPECT_NEAR(p[i], c[i], 1e-2) << i;
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
