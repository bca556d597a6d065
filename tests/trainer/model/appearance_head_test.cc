#include "trainer/model/appearance_head.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "trainer/model/positional_encoding.h"

namespace ecrf {
namespace trainer {
namespace {

// Scalar double-precision TensoRF MLPRender_Fea, written independently of the implementation.
struct Reference {
  AppearanceHeadConfig cfg;
  std::vector<double> params;  // same flat layout as AppearanceHead::params()
  size_t o_basis, o_w1, o_b1, o_w2, o_b2, o_w3, o_b3;
  int in_dim;

  Reference(const AppearanceHead& head) : cfg(head.config()) {
    params.assign(head.params().begin(), head.params().end());
    o_basis = head.basis_offset();
    o_w1 = head.w1_offset();
    o_b1 = head.b1_offset();
    o_w2 = head.w2_offset();
    o_b2 = head.b2_offset();
    o_w3 = head.w3_offset();
    o_b3 = head.b3_offset();
    in_dim = head.mlp_input_dim();
  }

  static void Pe(const std::vector<double>& x, int freqs, std::vector<double>* out) {
    std::vector<double> pts;
    for (double v : x) {
      for (int f = 0; f < freqs; ++f) pts.push_back(v * std::pow(2.0, f));
    }
    for (double p : pts) out->push_back(std::sin(p));
    for (double p : pts) out->push_back(std::cos(p));
  }

  // One sample. Appends the ReLU on/off pattern to *pattern if given.
  void Sample(const double* prod, const double* vd, double* rgb,
              std::vector<char>* pattern = nullptr) const {
    const int P = cfg.num_products, F = cfg.feature_dim, H = cfg.hidden;
    std::vector<double> feat(F, 0.0);
    for (int j = 0; j < F; ++j) {
      for (int k = 0; k < P; ++k) feat[j] += params[o_basis + j * P + k] * prod[k];
    }
    std::vector<double> view(vd, vd + 3);
    std::vector<double> in = feat;
    in.insert(in.end(), view.begin(), view.end());
    Pe(feat, cfg.feature_pe_freqs, &in);
    Pe(view, cfg.viewdir_pe_freqs, &in);
    if (static_cast<int>(in.size()) != in_dim) ADD_FAILURE() << "input width " << in.size();
    auto layer = [&](const std::vector<double>& a, size_t ow, size_t ob, int out, bool relu) {
      std::vector<double> z(out);
      for (int o = 0; o < out; ++o) {
        // Four partial sums: no long add latency chain (this reference runs thousands of times).
        const double* wrow = &params[ow + o * a.size()];
        double part[4] = {0.0, 0.0, 0.0, 0.0};
        size_t i = 0;
        for (; i + 4 <= a.size(); i += 4) {
          for (int u = 0; u < 4; ++u) part[u] += wrow[i + u] * a[i + u];
        }
        for (; i < a.size(); ++i) part[0] += wrow[i] * a[i];
        const double s = params[ob + o] + ((part[0] + part[1]) + (part[2] + part[3]));
        if (relu && pattern != nullptr) pattern->push_back(s > 0.0);
        z[o] = relu ? std::max(s, 0.0) : s;
      }
      return z;
    };
    const std::vector<double> h1 = layer(in, o_w1, o_b1, H, true);
    const std::vector<double> h2 = cfg.hidden_layers == 2 ? layer(h1, o_w2, o_b2, H, true) : h1;
    const std::vector<double> z3 = layer(h2, o_w3, o_b3, 3, false);
    for (int c = 0; c < 3; ++c) rgb[c] = 1.0 / (1.0 + std::exp(-z3[c]));
  }

  // L = sum g * rgb over the batch.
  double Loss(int n, const std::vector<double>& prod, const std::vector<double>& vd,
              const std::vector<double>& g, std::vector<char>* pattern = nullptr) const {
    double loss = 0.0;
    for (int i = 0; i < n; ++i) {
      double rgb[3];
      Sample(&prod[static_cast<size_t>(i) * cfg.num_products], &vd[3 * i], rgb, pattern);
      for (int c = 0; c < 3; ++c) loss += g[3 * i + c] * rgb[c];
    }
    return loss;
  }
};

struct Batch {
  int n;
  std::vector<float> products, viewdirs;
};

Batch RandomBatch(int n, int P, uint32_t seed, float product_scale = 1.0f) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  Batch b;
  b.n = n;
  b.products.resize(static_cast<size_t>(n) * P);
  for (float& v : b.products) v = product_scale * normal(rng);
  b.viewdirs.resize(3 * static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    float d[3] = {normal(rng), normal(rng), normal(rng)};
    const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int c = 0; c < 3; ++c) b.viewdirs[3 * i + c] = d[c] / len;
  }
  return b;
}

// Larger than default init so the sigmoid/ReLU work in a non-trivial regime.
void ScaleParams(AppearanceHead* head, float s) {
  for (float& p : head->params()) p *= s;
}

TEST(AppearanceHeadTest, LayoutAndWidth) {
  AppearanceHead head{AppearanceHeadConfig{}};
  EXPECT_EQ(head.mlp_input_dim(), 150);
  EXPECT_EQ(head.basis_offset(), 0u);
  EXPECT_EQ(head.w1_offset(), 27u * 144);
  EXPECT_EQ(head.b1_offset(), head.w1_offset() + 128u * 150);
  EXPECT_EQ(head.w2_offset(), head.b1_offset() + 128u);
  EXPECT_EQ(head.b2_offset(), head.w2_offset() + 128u * 128);
  EXPECT_EQ(head.w3_offset(), head.b2_offset() + 128u);
  EXPECT_EQ(head.b3_offset(), head.w3_offset() + 3u * 128);
  EXPECT_EQ(head.params().size(), head.b3_offset() + 3);
  EXPECT_EQ(head.grads().size(), head.params().size());
}

TEST(AppearanceHeadTest, InitializeIsDeterministicAndBounded) {
  AppearanceHeadConfig cfg;
  AppearanceHead a(cfg), b(cfg), c(cfg);
  a.Initialize(7);
  b.Initialize(7);
  c.Initialize(8);
  EXPECT_EQ(a.params(), b.params());
  EXPECT_NE(a.params(), c.params());
  auto check = [&](size_t begin, size_t count, double bound) {
    double max_abs = 0.0, sum = 0.0;
    for (size_t i = begin; i < begin + count; ++i) {
      max_abs = std::max(max_abs, std::fabs(static_cast<double>(a.params()[i])));
      sum += a.params()[i];
    }
    EXPECT_LE(max_abs, bound);
    EXPECT_GT(max_abs, 0.9 * bound);  // actually spans the range
    EXPECT_LT(std::fabs(sum / count), 0.2 * bound);
  };
  check(a.basis_offset(), 27 * 144, 1.0 / 12.0);
  check(a.w1_offset(), 128 * 150, 1.0 / std::sqrt(150.0));
  check(a.b1_offset(), 128, 1.0 / std::sqrt(150.0));
  check(a.w2_offset(), 128 * 128, 1.0 / std::sqrt(128.0));
  check(a.b2_offset(), 128, 1.0 / std::sqrt(128.0));
  check(a.w3_offset(), 3 * 128, 1.0 / std::sqrt(128.0));
  for (int k = 0; k < 3; ++k) EXPECT_EQ(a.params()[a.b3_offset() + k], 0.0f);
}

TEST(AppearanceHeadTest, ForwardMatchesNaiveReference) {
  AppearanceHeadConfig cfg;
  for (int chunk : {16, 256}) {
    AppearanceHead head(cfg);
    head.Initialize(3);
    ScaleParams(&head, 2.0f);
    head.set_chunk_rows(chunk);
    const Batch b = RandomBatch(301, cfg.num_products, 11, 0.5f);
    std::vector<float> rgb(3 * b.n, -1.0f);
    head.Forward(b.n, b.products.data(), b.viewdirs.data(), rgb.data());
    const Reference ref(head);
    double max_err = 0.0, spread = 0.0;
    for (int i = 0; i < b.n; ++i) {
      const std::vector<double> prod(b.products.begin() + i * cfg.num_products,
                                     b.products.begin() + (i + 1) * cfg.num_products);
      const std::vector<double> vd(b.viewdirs.begin() + 3 * i, b.viewdirs.begin() + 3 * i + 3);
      double expect[3];
      ref.Sample(prod.data(), vd.data(), expect);
      for (int c = 0; c < 3; ++c) {
        max_err = std::max(max_err, std::fabs(expect[c] - rgb[3 * i + c]));
        spread = std::max(spread, std::fabs(expect[c] - 0.5));
      }
    }
    EXPECT_LT(max_err, 1e-5) << "chunk " << chunk;
    EXPECT_GT(spread, 0.05);  // the outputs are not all ~0.5: the check means something
  }
}

TEST(AppearanceHeadTest, InferEqualsForward) {
  AppearanceHeadConfig cfg;
  AppearanceHead head(cfg);
  head.Initialize(5);
  ScaleParams(&head, 2.0f);
  for (int chunk : {16, 100, 256}) {
    head.set_chunk_rows(chunk);
    for (int n : {1, 17, 1000}) {
      const Batch b = RandomBatch(n, cfg.num_products, 100 + n);
      std::vector<float> fwd(3 * n), inf(3 * n);
      head.Forward(n, b.products.data(), b.viewdirs.data(), fwd.data());
      head.Infer(n, b.products.data(), b.viewdirs.data(), inf.data());
      for (int i = 0; i < 3 * n; ++i) ASSERT_FLOAT_EQ(fwd[i], inf[i]) << i;
    }
  }
}

// Central differences of the double reference against the float analytic gradients.
TEST(AppearanceHeadTest, GradientsMatchFiniteDifferences) {
  AppearanceHeadConfig cfg;
  AppearanceHead head(cfg);
  head.Initialize(21);
  ScaleParams(&head, 2.0f);
  head.set_chunk_rows(16);  // several chunks, so the per-thread gradient reduction is exercised
  const int n = 36;
  const int P = cfg.num_products;
  const Batch b = RandomBatch(n, P, 5, 0.5f);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> uni(-1.0f, 1.0f);
  std::vector<float> g(3 * n);
  for (float& v : g) v = uni(rng);

  std::vector<float> rgb(3 * n), dprod(static_cast<size_t>(n) * P);
  head.ZeroGrads();
  head.Forward(n, b.products.data(), b.viewdirs.data(), rgb.data());
  head.Backward(n, g.data(), dprod.data());
  const std::vector<float> grads = head.grads();

  Reference ref(head);
  std::vector<double> prod(b.products.begin(), b.products.end());
  const std::vector<double> vd(b.viewdirs.begin(), b.viewdirs.end());
  const std::vector<double> gd(g.begin(), g.end());
  const double h = 1e-5;
  int checked = 0, skipped = 0;
  // Returns false when the ReLU pattern differs between the two evaluations (a kink is within
  // h: the difference quotient would not be a derivative).
  // sample >= 0: only that sample depends on the perturbed value (a product entry).
  auto fd = [&](double* value, double* out, int sample = -1) {
    const double saved = *value;
    std::vector<char> pat_plus, pat_minus;
    auto loss = [&](std::vector<char>* pattern) {
      if (sample < 0) return ref.Loss(n, prod, vd, gd, pattern);
      double rgb3[3];
      ref.Sample(&prod[static_cast<size_t>(sample) * P], &vd[3 * sample], rgb3, pattern);
      return gd[3 * sample] * rgb3[0] + gd[3 * sample + 1] * rgb3[1] + gd[3 * sample + 2] * rgb3[2];
    };
    *value = saved + h;
    const double lp = loss(&pat_plus);
    *value = saved - h;
    const double lm = loss(&pat_minus);
    *value = saved;
    *out = (lp - lm) / (2 * h);
    return pat_plus == pat_minus;
  };
  auto expect_close = [&](double analytic, double numeric, const char* what, size_t idx) {
    EXPECT_NEAR(analytic, numeric, 2e-5 + 2e-4 * std::fabs(numeric)) << what << " " << idx;
    ++checked;
  };
  auto check_params = [&](const char* what, size_t offset, size_t count, size_t samples) {
    std::uniform_int_distribution<size_t> pick(0, count - 1);
    for (size_t s = 0; s < std::min(samples, count); ++s) {
      const size_t idx = offset + (samples >= count ? s : pick(rng));
      double numeric;
      if (!fd(&ref.params[idx], &numeric)) {
        ++skipped;
        continue;
      }
      expect_close(grads[idx], numeric, what, idx - offset);
    }
  };
  check_params("basis", head.basis_offset(), 27 * 144, 150);
  check_params("W1", head.w1_offset(), 128 * 150, 150);
  check_params("b1", head.b1_offset(), 128, 128);
  check_params("W2", head.w2_offset(), 128 * 128, 150);
  check_params("b2", head.b2_offset(), 128, 128);
  check_params("W3", head.w3_offset(), 3 * 128, 384);
  check_params("b3", head.b3_offset(), 3, 3);
  // dL/dproducts: all entries of a few samples, spread over the chunks.
  for (int i : {0, 15, 16, 35}) {
    for (int k = 0; k < P; ++k) {
      const size_t idx = static_cast<size_t>(i) * P + k;
      double numeric;
      if (!fd(&prod[idx], &numeric, i)) {
        ++skipped;
        continue;
      }
      expect_close(dprod[idx], numeric, "dproducts", idx);
    }
  }
  EXPECT_GT(checked, 1400);
  EXPECT_LT(skipped, checked / 50);
  // The gradients are not trivially zero.
  double norm = 0.0;
  for (float v : grads) norm += std::fabs(v);
  EXPECT_GT(norm, 1.0);
}

TEST(AppearanceHeadTest, PositionalEncodingValuesAndGradient) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> uni(-20.0f, 20.0f);
  for (int freqs : {1, 2, 3, 4}) {
    const int C = 5;
    std::vector<float> x(C);
    for (float& v : x) v = uni(rng);
    x[0] = 0.0f;
    std::vector<float> pe(2 * C * freqs);
    PositionalEncoding(x.data(), C, freqs, pe.data());
    for (int c = 0; c < C; ++c) {
      for (int f = 0; f < freqs; ++f) {
        const double a = static_cast<double>(x[c]) * std::pow(2.0, f);
        EXPECT_NEAR(pe[c * freqs + f], std::sin(a), 1e-6) << c << " " << f;
        EXPECT_NEAR(pe[C * freqs + c * freqs + f], std::cos(a), 1e-6) << c << " " << f;
      }
    }
    // Gradient of L = sum w * PE(x) against central differences of the double formula.
    std::vector<float> w(2 * C * freqs);
    for (float& v : w) v = uni(rng) / 20.0f;
    std::vector<float> dx(C, 0.5f);  // accumulates onto what is there
    PositionalEncodingBackward(pe.data(), w.data(), C, freqs, dx.data());
    for (int c = 0; c < C; ++c) {
      auto loss = [&](double xc) {
        double l = 0.0;
        for (int f = 0; f < freqs; ++f) {
          const double a = xc * std::pow(2.0, f);
          l += w[c * freqs + f] * std::sin(a) + w[C * freqs + c * freqs + f] * std::cos(a);
        }
        return l;
      };
      const double hh = 1e-6;
      const double numeric = (loss(x[c] + hh) - loss(x[c] - hh)) / (2 * hh);
      EXPECT_NEAR(dx[c] - 0.5f, numeric, 1e-5 * (1 + std::fabs(numeric))) << c;
    }
  }
}

TEST(AppearanceHeadTest, FastSinCosAccuracy) {
  std::mt19937 rng(2);
  std::vector<float> x;
  for (float range : {1.0f, 100.0f, 9000.0f, 1e6f}) {
    std::uniform_real_distribution<float> uni(-range, range);
    for (int i = 0; i < 20000; ++i) x.push_back(uni(rng));
  }
  x.push_back(0.0f);
  x.push_back(-0.0f);
  x.push_back(1.5707964f);
  x.push_back(-3.1415927f);
  std::vector<float> s(x.size()), c(x.size());
  FastSinCos(x.data(), static_cast<int>(x.size()), s.data(), c.data());
  for (size_t i = 0; i < x.size(); ++i) {
    ASSERT_NEAR(s[i], std::sin(static_cast<double>(x[i])), 2e-7) << x[i];
    ASSERT_NEAR(c[i], std::cos(static_cast<double>(x[i])), 2e-7) << x[i];
  }
}

TEST(AppearanceHeadTest, EmptyAndSingleBatch) {
  AppearanceHeadConfig cfg;
  AppearanceHead head(cfg);
  head.Initialize(1);
  head.ZeroGrads();
  head.Forward(0, nullptr, nullptr, nullptr);
  head.Backward(0, nullptr, nullptr);
  head.Infer(0, nullptr, nullptr, nullptr);
  for (float v : head.grads()) ASSERT_EQ(v, 0.0f);

  const Batch b = RandomBatch(1, cfg.num_products, 3);
  float rgb[3], inf[3], g[3] = {0.3f, -0.2f, 0.7f};
  std::vector<float> dprod(cfg.num_products);
  head.Forward(1, b.products.data(), b.viewdirs.data(), rgb);
  head.Infer(1, b.products.data(), b.viewdirs.data(), inf);
  const Reference ref(head);
  std::vector<double> prod(b.products.begin(), b.products.end());
  std::vector<double> vd(b.viewdirs.begin(), b.viewdirs.end());
  double expect[3];
  ref.Sample(prod.data(), vd.data(), expect);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(rgb[c], expect[c], 1e-6);
    EXPECT_EQ(rgb[c], inf[c]);
  }
  head.Backward(1, g, dprod.data());
  double norm = 0.0;
  for (float v : dprod) norm += std::fabs(v);
  EXPECT_GT(norm, 0.0);
  EXPECT_NE(head.grads()[head.b3_offset()], 0.0f);
}

TEST(AppearanceHeadTest, BackwardAccumulatesAndZeroGradsClears) {
  AppearanceHeadConfig cfg;
  AppearanceHead head(cfg);
  head.Initialize(2);
  const int n = 300;
  const Batch b = RandomBatch(n, cfg.num_products, 8);
  std::vector<float> rgb(3 * n), g(3 * n), d1(static_cast<size_t>(n) * cfg.num_products),
      d2(d1.size());
  std::mt19937 rng(1);
  for (float& v : g) v = std::uniform_real_distribution<float>(-1, 1)(rng);
  head.ZeroGrads();
  head.Forward(n, b.products.data(), b.viewdirs.data(), rgb.data());
  head.Backward(n, g.data(), d1.data());
  const std::vector<float> once = head.grads();
  head.Backward(n, g.data(), d2.data());
  EXPECT_EQ(d1, d2);  // dL/dproducts is written, not accumulated
  for (size_t i = 0; i < once.size(); ++i) {
    ASSERT_NEAR(head.grads()[i], 2.0f * once[i], 1e-6f * (1.0f + std::fabs(once[i]))) << i;
  }
  head.ZeroGrads();
  for (float v : head.grads()) ASSERT_EQ(v, 0.0f);
  EXPECT_THROW(head.Backward(n + 1, g.data(), d1.data()), std::logic_error);
}

TEST(AppearanceHeadTest, ThreadCountAndBorrowingDoNotChangeResults) {
  AppearanceHeadConfig cfg;
  const int n = 2000;
  const Batch b = RandomBatch(n, cfg.num_products, 12);
  std::vector<float> g(3 * n);
  std::mt19937 rng(3);
  for (float& v : g) v = std::uniform_real_distribution<float>(-1, 1)(rng);
  auto run = [&](int threads, bool borrow, std::vector<float>* rgb, std::vector<float>* dprod) {
    AppearanceHead head(cfg);
    head.Initialize(4);
    head.set_borrow_products(borrow);
    head.set_chunk_rows(64);
    const int saved = omp_get_max_threads();
    omp_set_num_threads(threads);
    rgb->resize(3 * n);
    dprod->resize(static_cast<size_t>(n) * cfg.num_products);
    head.ZeroGrads();
    head.Forward(n, b.products.data(), b.viewdirs.data(), rgb->data());
    head.Backward(n, g.data(), dprod->data());
    omp_set_num_threads(saved);
    return head.grads();
  };
  std::vector<float> rgb1, rgb2, rgb3, dp1, dp2, dp3;
  const std::vector<float> g1 = run(1, false, &rgb1, &dp1);
  const std::vector<float> g2 = run(2, false, &rgb2, &dp2);
  const std::vector<float> g3 = run(2, true, &rgb3, &dp3);
  // Rows are computed alike wherever their buffers sit, and the weight gradients are summed in
  // fixed runs of chunks: the same bits for every thread count, borrowed or copied inputs.
  EXPECT_EQ(rgb1, rgb2);
  EXPECT_EQ(rgb2, rgb3);
  EXPECT_EQ(dp1, dp2);
  EXPECT_EQ(dp2, dp3);
  EXPECT_EQ(g1, g2);
  EXPECT_EQ(g2, g3);
}

// Non-default widths and frequencies (odd feature PE count, no view PE), every parameter checked.
void CheckSmallConfigGradients(int hidden_layers) {
  AppearanceHeadConfig cfg;
  cfg.num_products = 10;
  cfg.feature_dim = 5;
  cfg.feature_pe_freqs = 3;
  cfg.viewdir_pe_freqs = 0;
  cfg.hidden = 16;
  cfg.hidden_layers = hidden_layers;
  AppearanceHead head(cfg);
  EXPECT_EQ(head.mlp_input_dim(), 5 + 3 + 2 * 3 * 5);
  const size_t second_layer = hidden_layers == 2 ? 16 * 16 + 16 : 0;
  EXPECT_EQ(head.num_params(), size_t(5 * 10 + 16 * 38 + 16) + second_layer + 3 * 16 + 3);
  head.Initialize(6);
  ScaleParams(&head, 2.0f);
  const int n = 9;
  const Batch b = RandomBatch(n, cfg.num_products, 2);
  std::vector<float> rgb(3 * n), g(3 * n, 0.0f), dprod(static_cast<size_t>(n) * cfg.num_products);
  for (int i = 0; i < 3 * n; ++i) g[i] = static_cast<float>((i * 7) % 5) / 5.0f - 0.4f;
  head.ZeroGrads();
  head.Forward(n, b.products.data(), b.viewdirs.data(), rgb.data());
  head.Backward(n, g.data(), dprod.data());
  Reference ref(head);
  std::vector<double> prod(b.products.begin(), b.products.end());
  const std::vector<double> vd(b.viewdirs.begin(), b.viewdirs.end());
  const std::vector<double> gd(g.begin(), g.end());
  for (int i = 0; i < n; ++i) {
    double expect[3];
    ref.Sample(&prod[static_cast<size_t>(i) * cfg.num_products], &vd[3 * i], expect);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(rgb[3 * i + c], expect[c], 1e-5);
  }
  const double h = 1e-5;
  int checked = 0;
  auto fd = [&](double* value) {
    const double saved = *value;
    std::vector<char> pp, pm;
    *value = saved + h;
    const double lp = ref.Loss(n, prod, vd, gd, &pp);
    *value = saved - h;
    const double lm = ref.Loss(n, prod, vd, gd, &pm);
    *value = saved;
    return pp == pm ? (lp - lm) / (2 * h) : NAN;
  };
  for (size_t i = 0; i < ref.params.size(); ++i) {
    const double numeric = fd(&ref.params[i]);
    if (std::isnan(numeric)) continue;
    EXPECT_NEAR(head.grads()[i], numeric, 2e-5 + 2e-4 * std::fabs(numeric)) << i;
    ++checked;
  }
  for (size_t i = 0; i < prod.size(); ++i) {
    const double numeric = fd(&prod[i]);
    if (std::isnan(numeric)) continue;
    EXPECT_NEAR(dprod[i], numeric, 2e-5 + 2e-4 * std::fabs(numeric)) << i;
    ++checked;
  }
  EXPECT_GT(checked, static_cast<int>(0.95 * (ref.params.size() + prod.size())));
}

TEST(AppearanceHeadTest, SmallConfigGradients) { CheckSmallConfigGradients(2); }

// One hidden layer (bitstream 1.8): W3 reads the first layer; no W2, b2.
TEST(AppearanceHeadTest, OneHiddenLayerGradients) { CheckSmallConfigGradients(1); }

// Pruning units of a one-layer head keeps their W1 rows, b1 entries and W3 columns, and the head
// computes what the full head computes with those units' weights zeroed.
TEST(AppearanceHeadTest, OneHiddenLayerKeepsUnits) {
  AppearanceHeadConfig cfg;
  cfg.num_products = 6;
  cfg.feature_dim = 4;
  cfg.hidden = 8;
  cfg.hidden_layers = 1;
  AppearanceHead head(cfg);
  head.Initialize(3);
  std::vector<uint8_t> keep(8, 1);
  keep[2] = keep[5] = 0;
  std::vector<uint8_t> other = keep;
  other[0] = 0;
  other[2] = 1;
  EXPECT_THROW(head.KeepHidden(keep, other), std::invalid_argument);  // one layer: the same units
  AppearanceHead zeroed = head;
  for (int u : {2, 5}) {
    const int in = head.mlp_input_dim();
    std::fill_n(zeroed.params().begin() + head.w1_offset() + size_t(u) * in, in, 0.f);
    zeroed.params()[head.b1_offset() + u] = 0.f;
  }
  head.KeepHidden(keep, keep);
  EXPECT_EQ(head.config().hidden, 6);
  const Batch b = RandomBatch(7, 6, 4);
  std::vector<float> a(21), z(21);
  head.Infer(7, b.products.data(), b.viewdirs.data(), a.data());
  zeroed.Infer(7, b.products.data(), b.viewdirs.data(), z.data());
  for (int i = 0; i < 21; ++i) EXPECT_NEAR(a[i], z[i], 1e-6) << i;
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
