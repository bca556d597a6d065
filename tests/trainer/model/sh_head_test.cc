// The appearance head with spherical-harmonics colour (hidden 0, SPEC.md 7.6.2) in training:
// gradients against finite differences of a double-precision reference, and the decoder's colour.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "decoder/mlp.h"
#include "decoder/sh_basis.h"
#include "trainer/model/appearance_head.h"

namespace ecrf {
namespace trainer {
namespace {

AppearanceHeadConfig ShHead(int degree, int products) {
  AppearanceHeadConfig c;
  c.num_products = products;
  return ShHeadConfig(c, degree);
}

struct Inputs {
  std::vector<float> products, viewdirs, g;
};

Inputs RandomInputs(int n, int P, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> nrm(0.f, 1.f);
  Inputs in;
  in.products.resize(size_t(n) * P);
  for (float& v : in.products) v = 0.7f * nrm(rng);
  for (int r = 0; r < n; ++r) {
    float d[3] = {nrm(rng), nrm(rng), nrm(rng)};
    const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (float v : d) in.viewdirs.push_back(v / len);
  }
  for (int i = 0; i < 3 * n; ++i) in.g.push_back(nrm(rng));
  return in;
}

// L = sum g . rgb in double, from the flat parameters (basis [F x P], then b3).
double ReferenceLoss(const AppearanceHeadConfig& c, const std::vector<double>& params,
                     const std::vector<double>& products, const Inputs& in) {
  const int P = c.num_products, F = c.feature_dim, K = F / 3;
  const int degree = static_cast<int>(std::lround(std::sqrt(double(K)))) - 1;
  const int n = static_cast<int>(in.viewdirs.size() / 3);
  double loss = 0.0;
  for (int r = 0; r < n; ++r) {
    float y[kMaxShFunctions];
    ShBasis(&in.viewdirs[size_t(r) * 3], degree, y);
    for (int ch = 0; ch < 3; ++ch) {
      double z = params[size_t(F) * P + ch];
      for (int k = 0; k < K; ++k) {
        double feat = 0.0;
        for (int p = 0; p < P; ++p)
          feat += params[size_t(ch * K + k) * P + p] * products[size_t(r) * P + p];
        z += y[k] * feat;
      }
      loss += in.g[size_t(r) * 3 + ch] / (1.0 + std::exp(-z));
    }
  }
  return loss;
}

TEST(ShHeadTest, GradientsMatchFiniteDifferences) {
  for (int degree : {0, 2, 3}) {
    const AppearanceHeadConfig cfg = ShHead(degree, 7);
    AppearanceHead head(cfg);
    head.Initialize(3 + degree);
    for (float& p : head.params()) p *= 3.f;  // out of the sigmoid's linear middle
    ASSERT_EQ(head.params().size(), size_t(cfg.feature_dim) * 7 + 3);
    head.set_chunk_rows(16);  // several chunks: the per-slot gradient sums are exercised
    const int n = 40;
    const Inputs in = RandomInputs(n, 7, 11 + degree);
    std::vector<float> rgb(3 * n), dprod(size_t(n) * 7);
    head.ZeroGrads();
    head.Forward(n, in.products.data(), in.viewdirs.data(), rgb.data());
    head.Backward(n, in.g.data(), dprod.data());
    std::vector<double> params(head.params().begin(), head.params().end());
    std::vector<double> prod(in.products.begin(), in.products.end());
    const double h = 1e-5;
    auto fd = [&](double* v) {
      const double saved = *v;
      *v = saved + h;
      const double lp = ReferenceLoss(cfg, params, prod, in);
      *v = saved - h;
      const double lm = ReferenceLoss(cfg, params, prod, in);
      *v = saved;
      return (lp - lm) / (2 * h);
    };
    double norm = 0.0;
    for (size_t i = 0; i < params.size(); ++i) {
      const double numeric = fd(&params[i]);
      EXPECT_NEAR(head.grads()[i], numeric, 1e-4 + 1e-4 * std::fabs(numeric))
          << "degree " << degree << " parameter " << i;
      norm += std::fabs(numeric);
    }
    EXPECT_GT(norm, 1.0);
    for (size_t i = 0; i < prod.size(); i += 3) {
      const double numeric = fd(&prod[i]);
      EXPECT_NEAR(dprod[i], numeric, 1e-4 + 1e-4 * std::fabs(numeric))
          << "degree " << degree << " product " << i;
    }
  }
}

// The trainer's Forward, its Infer and the decoder's colour agree (the basis sums in another
// order, so to rounding).
TEST(ShHeadTest, ForwardInferAndTheDecoderAgree) {
  const AppearanceHeadConfig cfg = ShHead(2, 30);
  AppearanceHead head(cfg);
  head.Initialize(8);
  const int n = 300;
  const Inputs in = RandomInputs(n, 30, 4);
  std::vector<float> fwd(3 * n), inf(3 * n), dec_rgb(3 * n);
  head.Forward(n, in.products.data(), in.viewdirs.data(), fwd.data());
  head.Infer(n, in.products.data(), in.viewdirs.data(), inf.data());
  dec::MlpConfig mc;
  mc.num_products = 30;
  mc.feature_dim = cfg.feature_dim;
  mc.feature_pe_freqs = 0;
  mc.viewdir_pe_freqs = 0;
  mc.hidden = 0;
  dec::AppearanceMlp mlp;
  ASSERT_TRUE(mlp.Init(mc).ok());
  ASSERT_TRUE(mlp.SetParams(head.params().data(), head.params().size()).ok());
  std::vector<float> scratch(mlp.ScratchFloats());
  mlp.Infer(n, in.products.data(), 30, in.viewdirs.data(), dec_rgb.data(), scratch.data());
  double spread = 0.0;
  for (int i = 0; i < 3 * n; ++i) {
    EXPECT_EQ(fwd[i], inf[i]) << i;
    EXPECT_NEAR(fwd[i], dec_rgb[i], 1e-6) << i;
    spread = std::max(spread, std::fabs(double(fwd[i]) - 0.5));
  }
  EXPECT_GT(spread, 0.05);
}

TEST(ShHeadTest, RefusesWidthsThatAreNoDegree) {
  AppearanceHeadConfig c = ShHead(1, 5);
  c.feature_dim = 11;
  EXPECT_THROW(AppearanceHead{c}, std::invalid_argument);
  c = ShHead(1, 5);
  c.viewdir_pe_freqs = 2;
  EXPECT_THROW(AppearanceHead{c}, std::invalid_argument);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
