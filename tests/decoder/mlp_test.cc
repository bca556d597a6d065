#include "decoder/mlp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "tests/common/naive_renderer.h"

namespace ecrf {
namespace dec {
namespace {

// Naive double-precision MLPRender_Fea on the trainer's flat parameter layout (the naive
// reference renderer's, tests/common/naive_renderer.h).
void NaiveMlp(const MlpConfig& cfg, const std::vector<float>& params, const float* prod,
              const float* vd, double rgb[3]) {
  naive::NaiveMlp(cfg, params, std::vector<double>(prod, prod + cfg.num_products), vd, rgb);
}

std::vector<float> RandomParams(const AppearanceMlp& mlp, uint32_t seed, float scale) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::vector<float> p(mlp.num_params());
  for (float& v : p) v = scale * u(rng);
  return p;
}

void RandomInputs(int rows, int P, uint32_t seed, std::vector<float>* prod,
                  std::vector<float>* vd) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.f, 1.f);
  prod->resize(static_cast<size_t>(rows) * (P > 0 ? P : 1));
  for (float& v : *prod) v = n(rng);
  vd->resize(static_cast<size_t>(rows) * 3);
  for (int r = 0; r < rows; ++r) {
    float d[3] = {n(rng), n(rng), n(rng)};
    const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int c = 0; c < 3; ++c) (*vd)[r * 3 + c] = d[c] / len;
  }
}

void CheckAgainstNaive(const MlpConfig& cfg, int rows, uint32_t seed) {
  AppearanceMlp mlp;
  ASSERT_TRUE(mlp.Init(cfg).ok());
  // Scale so hidden activations are O(1) and the sigmoid is not saturated.
  const std::vector<float> params = RandomParams(mlp, seed, 0.25f);
  ASSERT_TRUE(mlp.SetParams(params.data(), params.size()).ok());
  std::vector<float> prod, vd;
  RandomInputs(rows, cfg.num_products, seed + 1, &prod, &vd);
  const size_t stride = cfg.num_products > 0 ? cfg.num_products : 1;
  std::vector<float> rgb(static_cast<size_t>(rows) * 3, -1.f), scratch(mlp.ScratchFloats());
  mlp.Infer(rows, prod.data(), stride, vd.data(), rgb.data(), scratch.data());
  double max_err = 0.0;
  for (int r = 0; r < rows; ++r) {
    double ref[3];
    NaiveMlp(cfg, params, prod.data() + r * stride, vd.data() + r * 3, ref);
    for (int c = 0; c < 3; ++c) max_err = std::max(max_err, std::fabs(ref[c] - rgb[r * 3 + c]));
  }
  EXPECT_LT(max_err, 2e-5) << "P=" << cfg.num_products << " F=" << cfg.feature_dim
                           << " H=" << cfg.hidden;
  // Every row is computed independently of the batch: one row at a time gives the same bits.
  for (int r = 0; r < rows; r += 7) {
    float one[3];
    mlp.Infer(1, prod.data() + r * stride, stride, vd.data() + r * 3, one, scratch.data());
    for (int c = 0; c < 3; ++c) EXPECT_EQ(one[c], rgb[r * 3 + c]) << "row " << r;
  }
}

// GetParams gives back the MLPW layout bit for bit (the MLP checksum of SPEC.md 6.5 hashes it).
TEST(MlpTest, GetParamsReturnsExactlyWhatWasLoaded) {
  for (const int hidden : {1, 20, 128}) {
    MlpConfig cfg;
    cfg.num_products = 7;
    cfg.feature_dim = 5;
    cfg.hidden = hidden;
    AppearanceMlp mlp;
    ASSERT_TRUE(mlp.Init(cfg).ok());
    const std::vector<float> params = RandomParams(mlp, 9, 1.f);
    ASSERT_TRUE(mlp.SetParams(params.data(), params.size()).ok());
    std::vector<float> back(params.size(), -7.f);
    ASSERT_TRUE(mlp.GetParams(back.data(), back.size()).ok());
    EXPECT_EQ(std::memcmp(back.data(), params.data(), params.size() * sizeof(float)), 0) << hidden;
    EXPECT_EQ(mlp.GetParams(back.data(), back.size() + 1).code(), kErrInvalidArgument);
  }
}

TEST(MlpTest, DefaultTensorfWidthsMatchNaive) {
  MlpConfig cfg;
  cfg.num_products = 144;
  CheckAgainstNaive(cfg, 101, 1);  // several chunks and a ragged tail
}

TEST(MlpTest, OtherWidthsMatchNaive) {
  MlpConfig cfg;
  cfg.num_products = 7;
  cfg.feature_dim = 5;
  cfg.feature_pe_freqs = 3;
  cfg.viewdir_pe_freqs = 1;
  cfg.hidden = 20;
  CheckAgainstNaive(cfg, 33, 2);
  cfg.feature_pe_freqs = 0;
  cfg.viewdir_pe_freqs = 0;
  cfg.hidden = 1;
  CheckAgainstNaive(cfg, 5, 3);
}

TEST(MlpTest, ZeroProducts) {
  MlpConfig cfg;
  cfg.num_products = 0;
  cfg.hidden = 16;
  CheckAgainstNaive(cfg, 9, 4);
}

// The AVX2 and AVX-512 kernels compute more columns side by side with the same per-element
// arithmetic: the same bits as the portable kernel, for widths that fill none, some or all of
// their wide blocks (hidden 1, 20, 40, 128, 200; feature dims 5 and 27).
TEST(MlpTest, EveryGemmKernelGivesThePortableKernelsBits) {
  int checked = 0;
  for (const GemmKernel kernel : {GemmKernel::kAvx2, GemmKernel::kAvx512}) {
    if (!GemmKernelAvailable(kernel)) {
      AppearanceMlp mlp;
      ASSERT_TRUE(mlp.Init(MlpConfig()).ok());
      EXPECT_EQ(mlp.UseGemmKernel(kernel).code(), kErrInvalidArgument);
      continue;
    }
    for (const int hidden : {1, 20, 40, 128, 200}) {
      for (const int feature_dim : {5, 27}) {
        SCOPED_TRACE(std::string(GemmKernelName(kernel)) + " hidden " + std::to_string(hidden) +
                     " features " + std::to_string(feature_dim));
        MlpConfig cfg;
        cfg.num_products = 48;
        cfg.feature_dim = feature_dim;
        cfg.hidden = hidden;
        AppearanceMlp portable, wide;
        ASSERT_TRUE(portable.Init(cfg).ok());
        ASSERT_TRUE(wide.Init(cfg).ok());
        ASSERT_TRUE(portable.UseGemmKernel(GemmKernel::kPortable).ok());
        ASSERT_TRUE(wide.UseGemmKernel(kernel).ok());
        EXPECT_EQ(wide.gemm_kernel(), kernel);
        const std::vector<float> params = RandomParams(portable, 11 + hidden, 0.5f);
        ASSERT_TRUE(portable.SetParams(params.data(), params.size()).ok());
        ASSERT_TRUE(wide.SetParams(params.data(), params.size()).ok());
        std::vector<float> prod, vd;
        const int rows = 70;
        RandomInputs(rows, cfg.num_products, 5, &prod, &vd);
        std::vector<float> a(rows * 3), b(rows * 3, -1.f), scratch(portable.ScratchFloats());
        portable.Infer(rows, prod.data(), cfg.num_products, vd.data(), a.data(), scratch.data());
        wide.Infer(rows, prod.data(), cfg.num_products, vd.data(), b.data(), scratch.data());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0);
        ++checked;
      }
    }
  }
  std::printf("  %d configurations checked; widest kernel here: %s\n", checked,
              GemmKernelName(BestGemmKernel()));
}

TEST(MlpTest, RejectsBadConfigAndParams) {
  AppearanceMlp mlp;
  MlpConfig cfg;
  cfg.num_products = 10;
  cfg.hidden = 0;
  EXPECT_EQ(mlp.Init(cfg).code(), kErrLimit);
  cfg.hidden = kMaxMlpHidden + 1;
  EXPECT_EQ(mlp.Init(cfg).code(), kErrLimit);
  cfg.hidden = 8;
  cfg.num_products = -1;
  EXPECT_EQ(mlp.Init(cfg).code(), kErrLimit);
  cfg.num_products = 10;
  ASSERT_TRUE(mlp.Init(cfg).ok());
  std::vector<float> p(mlp.num_params(), 0.f);
  EXPECT_EQ(mlp.SetParams(p.data(), p.size() - 1).code(), kErrInvalidArgument);
  p[3] = NAN;
  EXPECT_EQ(mlp.SetParams(p.data(), p.size()).code(), kErrCorrupt);
  p[3] = 0.f;
  EXPECT_TRUE(mlp.SetParams(p.data(), p.size()).ok());
  // Moves keep the weights.
  AppearanceMlp moved(static_cast<AppearanceMlp&&>(mlp));
  EXPECT_TRUE(moved.initialized());
  EXPECT_FALSE(mlp.initialized());
}

TEST(MlpTest, FastSinCosAccuracy) {
  std::vector<float> x;
  for (int i = -20000; i <= 20000; ++i) x.push_back(i * 0.013f);
  x.push_back(1e5f);
  x.push_back(-3e6f);
  x.push_back(0.f);
  x.push_back(-0.f);
  std::vector<float> s(x.size()), c(x.size());
  FastSinCos(x.data(), static_cast<int>(x.size()), s.data(), c.data());
  double max_err = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    max_err = std::max(max_err, std::fabs(s[i] - std::sin(double(x[i]))));
    max_err = std::max(max_err, std::fabs(c[i] - std::cos(double(x[i]))));
  }
  EXPECT_LT(max_err, 5e-7);
}

}  // namespace
}  // namespace dec
}  // namespace ecrf
