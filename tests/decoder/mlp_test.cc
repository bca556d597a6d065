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

// One hidden layer (MLPW layers 1, SPEC.md 6.6): W3 reads the first layer.
TEST(MlpTest, OneHiddenLayerMatchesNaive) {
  MlpConfig cfg;
  cfg.num_products = 144;
  cfg.hidden_layers = 1;
  CheckAgainstNaive(cfg, 45, 9);
  cfg.hidden = 20;
  cfg.feature_pe_freqs = 0;
  CheckAgainstNaive(cfg, 17, 10);
  AppearanceMlp mlp;
  ASSERT_TRUE(mlp.Init(cfg).ok());
  const size_t F = 27, P = 144, H = 20, in = cfg.input_dim();
  EXPECT_EQ(mlp.num_params(), F * P + H * in + H + 3 * H + 3);
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

// SPEC.md 7.6 in plain float arithmetic: every dot product from the bias in increasing k over
// every term, one rounded multiply and one rounded add each (this file builds with
// -ffp-contract=off), the positional encoding through FastSinCos as the reference renderer's.
void ScalarReferenceMlp(const MlpConfig& cfg, const std::vector<float>& params, const float* prod,
                        const float* vd, float rgb[3]) {
  const int P = cfg.num_products, F = cfg.feature_dim, H = cfg.hidden, in = cfg.input_dim();
  const int H2 = cfg.hidden_layers == 2 ? H : 0;
  const float* basis = params.data();
  const float* w1 = basis + static_cast<size_t>(F) * P;
  const float* b1 = w1 + static_cast<size_t>(H) * in;
  const float* w2 = b1 + H;
  const float* b2 = w2 + static_cast<size_t>(H2) * H2;
  const float* w3 = b2 + H2;
  const float* b3 = w3 + 3 * H;
  std::vector<float> x;
  std::vector<float> feat(F);
  for (int j = 0; j < F; ++j) {
    float s = 0.f;
    for (int k = 0; k < P; ++k) s += basis[j * P + k] * prod[k];
    feat[j] = s;
  }
  std::vector<float> af, av;
  for (int c = 0; c < F; ++c) {
    for (int q = 0; q < cfg.feature_pe_freqs; ++q) af.push_back(feat[c] * std::ldexp(1.f, q));
  }
  for (int c = 0; c < 3; ++c) {
    for (int q = 0; q < cfg.viewdir_pe_freqs; ++q) av.push_back(vd[c] * std::ldexp(1.f, q));
  }
  std::vector<float> sf(af.size()), cf(af.size()), sv(av.size()), cv(av.size());
  FastSinCos(af.data(), static_cast<int>(af.size()), sf.data(), cf.data());
  FastSinCos(av.data(), static_cast<int>(av.size()), sv.data(), cv.data());
  x = feat;
  x.insert(x.end(), vd, vd + 3);
  for (const auto* part : {&sf, &cf, &sv, &cv}) x.insert(x.end(), part->begin(), part->end());
  std::vector<float> h1(H), h2(H);
  for (int o = 0; o < H; ++o) {
    float s = b1[o];
    for (int k = 0; k < in; ++k) s += w1[o * in + k] * x[k];
    h1[o] = s > 0.f ? s : 0.f;
  }
  for (int o = 0; o < H2; ++o) {
    float s = b2[o];
    for (int k = 0; k < H; ++k) s += w2[o * H + k] * h1[k];
    h2[o] = s > 0.f ? s : 0.f;
  }
  if (H2 == 0) h2 = h1;  // one hidden layer: W3 reads the first
  for (int c = 0; c < 3; ++c) {
    float s = b3[c];
    for (int k = 0; k < H; ++k) s += w3[c * H + k] * h2[k];
    rgb[c] = 1.f / (1.f + std::exp(-s));
  }
}

// The hidden layers skip the inputs that are zero in all 8 rows of a block (decoder/mlp.cc). With
// biases that switch off most units (and some units dead in every row) the output must still be
// the reference's bits, on every kernel, for batches of any size.
void CheckSkippingZerosGivesTheReferenceBits(int hidden, int layers) {
  MlpConfig cfg;
  cfg.num_products = 48;
  cfg.hidden = hidden;
  cfg.hidden_layers = layers;
  AppearanceMlp mlp;
  ASSERT_TRUE(mlp.Init(cfg).ok());
  std::vector<float> params = RandomParams(mlp, 21 + hidden, 0.3f);
  const int F = cfg.feature_dim, P = cfg.num_products, H = hidden, in = cfg.input_dim();
  float* b1 = params.data() + static_cast<size_t>(F) * P + static_cast<size_t>(H) * in;
  float* b2 = b1 + H + static_cast<size_t>(H) * H;  // two hidden layers only
  for (int o = 0; o < H; ++o) {
    b1[o] = o % 3 == 0 ? -100.f : b1[o] - 0.6f;  // every third unit dead, the rest mostly off
    if (layers == 2) b2[o] = o % 4 == 0 ? -100.f : b2[o] - 0.3f;
  }
  ASSERT_TRUE(mlp.SetParams(params.data(), params.size()).ok());
  std::vector<float> prod, vd;
  const int rows = 77;
  RandomInputs(rows, P, 8, &prod, &vd);
  std::vector<float> ref(rows * 3);
  for (int r = 0; r < rows; ++r)
    ScalarReferenceMlp(cfg, params, prod.data() + r * P, vd.data() + r * 3, &ref[r * 3]);
  for (const GemmKernel kernel : {GemmKernel::kPortable, GemmKernel::kAvx2, GemmKernel::kAvx512}) {
    if (!GemmKernelAvailable(kernel)) continue;
    SCOPED_TRACE(std::string(GemmKernelName(kernel)) + " hidden " + std::to_string(hidden));
    ASSERT_TRUE(mlp.UseGemmKernel(kernel).ok());
    std::vector<float> rgb(rows * 3, -1.f), scratch(mlp.ScratchFloats());
    mlp.Infer(rows, prod.data(), P, vd.data(), rgb.data(), scratch.data());
    EXPECT_EQ(std::memcmp(rgb.data(), ref.data(), rgb.size() * sizeof(float)), 0);
    for (int r = 0; r < rows; r += 5) {
      float one[3];
      mlp.Infer(1, prod.data() + r * P, P, vd.data() + r * 3, one, scratch.data());
      EXPECT_EQ(std::memcmp(one, &ref[r * 3], sizeof(one)), 0) << "row " << r;
    }
  }
}

TEST(MlpTest, SkippingZeroActivationsGivesTheReferenceBits) {
  for (const int layers : {2, 1}) {
    for (const int hidden : {20, 128}) {
      SCOPED_TRACE(std::to_string(layers) + " hidden layers");
      CheckSkippingZerosGivesTheReferenceBits(hidden, layers);
    }
  }
}

// Which columns a block of 8 rows must sum over: +0 and -0 are skipped, anything else is kept
// (denormals, NaN, infinities), in increasing order.
TEST(MlpTest, NonZeroColumnsKeepsEveryValueThatIsNotZero) {
  const int K = 150;  // more than one internal step of 64
  std::vector<float> rows(8 * K, 0.f);
  for (int k = 0; k < K; ++k) rows[(k % 8) * K + k] = k % 2 == 0 ? -0.f : 0.f;
  const std::vector<int> kept = {3, 64, 65, 100, 149};
  rows[0 * K + 3] = 1e-40f;  // denormal
  rows[7 * K + 64] = std::nanf("");
  rows[5 * K + 65] = -INFINITY;
  rows[2 * K + 100] = -2.5f;
  rows[1 * K + 149] = 7.f;
  const float* x[8];
  for (int r = 0; r < 8; ++r) x[r] = rows.data() + r * K;
  std::vector<int> ks(K, -1);
  const int nk = NonZeroColumns8(x, K, ks.data());
  ASSERT_EQ(nk, static_cast<int>(kept.size()));
  for (int i = 0; i < nk; ++i) EXPECT_EQ(ks[i], kept[i]);
}

TEST(MlpTest, RejectsBadConfigAndParams) {
  AppearanceMlp mlp;
  MlpConfig cfg;
  cfg.num_products = 10;
  cfg.hidden = -1;
  EXPECT_EQ(mlp.Init(cfg).code(), kErrLimit);
  cfg.hidden = 0;  // spherical harmonics: 27 features suit degree 2, the encodings do not
  EXPECT_EQ(mlp.Init(cfg).code(), kErrInvalidArgument);
  cfg.hidden = kMaxMlpHidden + 1;
  EXPECT_EQ(mlp.Init(cfg).code(), kErrLimit);
  cfg.hidden = 8;
  cfg.num_products = -1;
  EXPECT_EQ(mlp.Init(cfg).code(), kErrLimit);
  cfg.num_products = 10;
  for (const int layers : {0, 3}) {
    cfg.hidden_layers = layers;
    EXPECT_EQ(mlp.Init(cfg).code(), kErrInvalidArgument) << layers << " hidden layers";
  }
  cfg.hidden_layers = 2;
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
