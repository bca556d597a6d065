#include "trainer/rate/entropy_model.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <map>
#include <random>
#include <vector>

#include "trainer/train/adam.h"

namespace ecrf {
namespace trainer {
namespace {

// Random parameters, including non-zero factors, so every parameter kind matters.
void Randomize(FactorizedEntropyModel* m, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> nd(0.f, 0.7f);
  for (float& p : m->params()) p = nd(rng);
}

TEST(EntropyModelTest, InitMatchesCompressAI) {
  FactorizedEntropyModel m;
  m.Init(4, 1);
  const double scale = std::pow(10.0, 0.25);
  const float init3 = static_cast<float>(std::log(std::expm1(1.0 / scale / 3.0)));
  const float init1 = static_cast<float>(std::log(std::expm1(1.0 / scale / 1.0)));
  for (int c = 0; c < 4; ++c) {
    const float* p = m.model_params(c);
    for (int i = 0; i < 21; ++i) EXPECT_FLOAT_EQ(p[i], init3);
    for (int i = 21; i < 24; ++i) EXPECT_FLOAT_EQ(p[i], init1);
    for (int i = 24; i < 34; ++i) {
      EXPECT_GE(p[i], -0.5f);
      EXPECT_LE(p[i], 0.5f);
    }
    for (int i = 34; i < 43; ++i) EXPECT_EQ(p[i], 0.f);
  }
  EXPECT_NE(m.model_params(0)[24], m.model_params(1)[24]);
  // At init the CDF spans roughly +-init_scale: the median sits near 0 and c(+-10*3) ~ 1 / 0.
  EXPECT_LT(1.0 / (1.0 + std::exp(-m.LogitsCumulative(0, -30.0))), 0.1);
  EXPECT_GT(1.0 / (1.0 + std::exp(-m.LogitsCumulative(0, 30.0))), 0.9);
}

// Finite differences only where the likelihood is above the lower bound (below it the value is
// constant while CompressAI's bound passes a gradient; see LowerBoundGradient).
TEST(EntropyModelTest, BitsDoubleGradientWrtXMatchesFiniteDifferences) {
  int checked = 0;
  for (uint32_t seed : {1u, 2u, 3u}) {
    FactorizedEntropyModel m;
    m.Init(2, seed);
    if (seed > 1) Randomize(&m, seed);
    for (double x : {-7.3, -2.0, -0.4, 0.0, 0.3, 1.7, 5.5, 12.25}) {
      if (m.Likelihood(1, x) < 1e-7) continue;
      ++checked;
      double dx = 0.0;
      m.BitsDouble(1, x, &dx, nullptr);
      const double h = 1e-5;
      const double fd =
          (m.BitsDouble(1, x + h, nullptr, nullptr) - m.BitsDouble(1, x - h, nullptr, nullptr)) /
          (2 * h);
      EXPECT_NEAR(dx, fd, 1e-6 * (1.0 + std::abs(fd))) << "seed " << seed << " x " << x;
    }
  }
  EXPECT_GE(checked, 16);
}

TEST(EntropyModelTest, BitsDoubleGradientWrtEveryParameterMatchesFiniteDifferences) {
  FactorizedEntropyModel m;
  m.Init(1, 7);
  Randomize(&m, 7);
  int checked = 0;
  for (double x : {-3.0, -1.1, -0.6, 0.2, 1.3, 2.4}) {
    if (m.Likelihood(0, x) < 1e-7) continue;
    ++checked;
    std::vector<double> g(kEntropyParamsPerModel, 0.0);
    m.BitsDouble(0, x, nullptr, g.data());
    for (int i = 0; i < kEntropyParamsPerModel; ++i) {
      float& p = m.params()[i];
      const float orig = p;
      p = orig + 1e-3f;
      const double hp = double(p) - double(orig);
      const double up = m.BitsDouble(0, x, nullptr, nullptr);
      p = orig - 1e-3f;
      const double hm = double(orig) - double(p);
      const double dn = m.BitsDouble(0, x, nullptr, nullptr);
      p = orig;
      const double fd = (up - dn) / (hp + hm);
      EXPECT_NEAR(g[i], fd, 2e-5 * (1.0 + std::abs(fd))) << "param " << i << " x " << x;
    }
  }
  EXPECT_GE(checked, 3);
}

// The vectorised float path agrees with the double path (values, dx, parameter gradients).
TEST(EntropyModelTest, FloatPathMatchesDoublePath) {
  FactorizedEntropyModel m;
  m.Init(3, 11);
  Randomize(&m, 12);
  std::mt19937 rng(5);
  std::normal_distribution<float> nd(0.f, 4.f);
  const size_t n = 5000;  // several work items and a partial chunk
  std::vector<float> x(n);
  for (float& v : x) v = nd(rng);
  const EntropySegment segs[2] = {{2, 0, 3001}, {0, 3001, n}};
  std::vector<float> bits(n), dx(n);
  m.ZeroGrads();
  const double total = m.Bits(x.data(), segs, 2, bits.data(), dx.data(), 0.5f, true);
  double ref_total = 0.0;
  std::vector<double> ref_g(m.params().size(), 0.0);
  for (size_t i = 0; i < n; ++i) {
    const int model = i < 3001 ? 2 : 0;
    double d = 0.0;
    const double b = m.BitsDouble(model, x[i], &d, ref_g.data() + model * kEntropyParamsPerModel);
    ref_total += b;
    ASSERT_NEAR(bits[i], b, 2e-5 * (1.0 + b)) << i;
    ASSERT_NEAR(dx[i], 0.5 * d, 2e-4 * (1.0 + std::abs(d))) << i;
  }
  EXPECT_NEAR(total, ref_total, 1e-5 * ref_total);
  for (size_t i = 0; i < ref_g.size(); ++i) {
    EXPECT_NEAR(m.grads()[i], 0.5 * ref_g[i], 1e-3 * (1.0 + std::abs(ref_g[i]))) << "param " << i;
  }
  // Model 1 has no samples: no gradient.
  for (int i = 0; i < kEntropyParamsPerModel; ++i)
    EXPECT_EQ(m.grads()[kEntropyParamsPerModel + i], 0.f);
  // Without gradient outputs the value is the same and grads stay untouched.
  const std::vector<float> before = m.grads();
  EXPECT_DOUBLE_EQ(m.Bits(x.data(), segs, 2, nullptr, nullptr, 1.f, false), total);
  EXPECT_EQ(m.grads(), before);
}

TEST(EntropyModelTest, CdfIsMonotoneForRandomParameters) {
  for (uint32_t seed = 0; seed < 20; ++seed) {
    FactorizedEntropyModel m;
    m.Init(1, seed);
    Randomize(&m, 100 + seed);
    double prev = -1e300;
    for (double x = -60.0; x <= 60.0; x += 0.01) {
      const double l = m.LogitsCumulative(0, x);
      ASSERT_GT(l, prev) << "seed " << seed << " x " << x;
      prev = l;
    }
  }
}

TEST(EntropyModelTest, LikelihoodsOfAllIntegersSumToOne) {
  for (uint32_t seed = 0; seed < 5; ++seed) {
    FactorizedEntropyModel m;
    m.Init(1, seed);
    if (seed > 0) Randomize(&m, 200 + seed);
    double sum = 0.0;
    for (int k = -3000; k <= 3000; ++k) sum += m.Likelihood(0, k);
    // Telescoping sum of c(k+1/2) - c(k-1/2); the lower bound adds at most 6001e-9.
    EXPECT_NEAR(sum, 1.0, 1e-3) << "seed " << seed;
    // bits = -log2(likelihood) on both paths.
    const float x = 1.f;
    EXPECT_NEAR(m.Bits(0, &x, 1, nullptr, nullptr, 0.f, false), -std::log2(m.Likelihood(0, 1.0)),
                1e-4);
  }
}

TEST(EntropyModelTest, LowerBoundGradient) {
  FactorizedEntropyModel pass, block;
  pass.Init(1, 3);
  EntropyModelOptions opt;
  opt.pass_gradient_if_increasing = false;
  block.Init(1, 3, opt);
  // Find a tail point whose raw likelihood is below the bound but not zero.
  double x = 1.0;
  for (; x < 1e5; x += 1.0) {
    if (pass.Likelihood(0, x) <= 1e-9 * 1.0000001) break;
  }
  ASSERT_LT(x, 1e5);
  const double bound_bits = -std::log2(static_cast<double>(1e-9f));
  double dpass = 0.0, dblock = 0.0;
  std::vector<double> gpass(kEntropyParamsPerModel, 0.0), gblock(kEntropyParamsPerModel, 0.0);
  EXPECT_NEAR(pass.BitsDouble(0, x + 3, &dpass, gpass.data()), bound_bits, 1e-9);
  EXPECT_NEAR(block.BitsDouble(0, x + 3, &dblock, gblock.data()), bound_bits, 1e-9);
  // CompressAI semantics: the gradient still flows and pulls x back towards the bulk (bits
  // would fall as x decreases), and moves the parameters; blocked variant: exactly zero.
  EXPECT_GT(dpass, 0.0);
  EXPECT_EQ(dblock, 0.0);
  double norm = 0.0;
  for (int i = 0; i < kEntropyParamsPerModel; ++i) {
    norm += std::abs(gpass[i]);
    EXPECT_EQ(gblock[i], 0.0);
  }
  EXPECT_GT(norm, 0.0);
  // Below the bound the passed gradient is d(-log2 L)/dx scaled by L / bound (< true gradient).
  // Unclamped points: both variants agree.
  double a = 0.0, b = 0.0;
  pass.BitsDouble(0, 2.0, &a, nullptr);
  block.BitsDouble(0, 2.0, &b, nullptr);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, 0.0);
}

// Train one model with Adam on the noisy proxy of Laplacian samples; the rounded-sample code
// length approaches the empirical entropy of the rounded samples.
TEST(EntropyModelTest, TrainingOnLaplacianApproachesEmpiricalEntropy) {
  for (double b : {0.7, 3.0}) {
    std::mt19937 rng(42);
    std::exponential_distribution<double> ex(1.0 / b);
    std::bernoulli_distribution coin(0.5);
    const size_t n = 20000;
    std::vector<float> samples(n), rounded(n);
    std::map<int, int> hist;
    for (size_t i = 0; i < n; ++i) {
      samples[i] = static_cast<float>(coin(rng) ? ex(rng) : -ex(rng));
      rounded[i] = std::round(samples[i]);
      ++hist[static_cast<int>(rounded[i])];
    }
    double entropy = 0.0;
    for (const auto& kv : hist) {
      const double p = double(kv.second) / n;
      entropy -= p * std::log2(p);
    }
    FactorizedEntropyModel m;
    m.Init(1, 9);
    Adam adam(m.params().size(), AdamConfig{});
    std::uniform_real_distribution<float> u(-0.5f, 0.5f);
    std::vector<float> noisy(n);
    for (int step = 0; step < 400; ++step) {
      for (size_t i = 0; i < n; ++i) noisy[i] = samples[i] + u(rng);
      m.ZeroGrads();
      m.Bits(0, noisy.data(), n, nullptr, nullptr, 1.f / n, true);
      adam.Step(m.params().data(), m.grads().data(), m.params().size(),
                step < 300 ? 0.02f : 0.005f);
    }
    const double bits = m.Bits(0, rounded.data(), n, nullptr, nullptr, 0.f, false) / n;
    std::printf("[laplace b=%.1f] empirical entropy %.4f bits, model %.4f bits/sample\n", b,
                entropy, bits);
    EXPECT_GE(bits, entropy - 1e-6);
    EXPECT_LT(bits, entropy + 0.1);
  }
}

TEST(EntropyModelTest, SpeedPerCoefficient) {
  FactorizedEntropyModel m;
  m.Init(8, 1);
  const size_t n = 1 << 21;
  std::vector<float> x(n), dx(n);
  std::mt19937 rng(1);
  std::normal_distribution<float> nd(0.f, 5.f);
  for (float& v : x) v = nd(rng);
  std::vector<EntropySegment> segs;
  for (int c = 0; c < 8; ++c) segs.push_back({c, n / 8 * c, n / 8 * (c + 1)});
  // Wall time and process CPU time (the CPU time is meaningful on a loaded machine).
  double best_fb = 1e9, best_f = 1e9, cpu_fb = 1e9, cpu_f = 1e9;
  for (int rep = 0; rep < 3; ++rep) {
    auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    m.Bits(x.data(), segs.data(), 8, nullptr, dx.data(), 1.f, true);
    auto t1 = std::chrono::steady_clock::now();
    const std::clock_t c1 = std::clock();
    m.Bits(x.data(), segs.data(), 8, nullptr, nullptr, 1.f, false);
    auto t2 = std::chrono::steady_clock::now();
    const std::clock_t c2 = std::clock();
    best_fb = std::min(best_fb, std::chrono::duration<double>(t1 - t0).count());
    best_f = std::min(best_f, std::chrono::duration<double>(t2 - t1).count());
    cpu_fb = std::min(cpu_fb, double(c1 - c0) / CLOCKS_PER_SEC);
    cpu_f = std::min(cpu_f, double(c2 - c1) / CLOCKS_PER_SEC);
  }
  std::printf(
      "[speed] entropy model: forward+backward %.2f ns/coef wall (%.2f CPU-ns), forward "
      "only %.2f ns/coef wall (%.2f CPU-ns)\n",
      best_fb * 1e9 / n, cpu_fb * 1e9 / n, best_f * 1e9 / n, cpu_f * 1e9 / n);
  EXPECT_GT(best_fb, 0.0);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
