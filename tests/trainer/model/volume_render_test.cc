#include "trainer/model/volume_render.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "tests/common/small_model.h"
#include "trainer/train/adam.h"

namespace ecrf {
namespace trainer {
namespace {

TEST(VolumeRenderTest, CompositeBackwardMatchesFiniteDifferences) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int n = 12;
  std::vector<double> alpha(n), e(n);
  for (int i = 0; i < n; ++i) {
    alpha[i] = u(rng) * 0.9;
    e[i] = u(rng) - 0.5;
  }
  alpha[3] = 0.0;
  alpha[7] = 0.999;
  auto forward = [&](const std::vector<double>& a, std::vector<double>* trans) {
    double T = 1, L = 0;
    if (trans) trans->resize(n);
    for (int i = 0; i < n; ++i) {
      if (trans) (*trans)[i] = T;
      L += a[i] * T * e[i];
      T *= (1 - a[i]) + 1e-10;
    }
    return L;
  };
  std::vector<double> trans, grad(n);
  forward(alpha, &trans);
  CompositeBackward(n, alpha.data(), trans.data(), e.data(), grad.data());
  for (int i = 0; i < n; ++i) {
    std::vector<double> a = alpha;
    const double eps = 1e-6;
    a[i] = alpha[i] + eps;
    const double lp = forward(a, nullptr);
    a[i] = alpha[i] - eps;
    const double lm = forward(a, nullptr);
    EXPECT_NEAR(grad[i], (lp - lm) / (2 * eps), 1e-8) << i;
  }
}

TEST(VolumeRenderTest, EmptyFieldRendersWhite) {
  TensorfModel model(testing_models::TinyTensorfConfig());
  model.Initialize({8, 8, 8}, 1);
  std::fill(model.density().params().begin(), model.density().params().end(), 0.f);
  std::vector<float> o, d;
  testing_models::RaysFromSphere(64, 2, &o, &d);
  std::vector<float> rgb(3 * 64), depth(64);
  RenderRays(model, 64, o.data(), d.data(), rgb.data(), depth.data());
  for (float v : rgb) EXPECT_GT(v, 0.99f);  // sigma = softplus(-10) is not exactly 0
  model.UpdateAlphaMask({8, 8, 8});
  ASSERT_TRUE(model.alpha_mask()->empty());
  RenderRays(model, 64, o.data(), d.data(), rgb.data(), depth.data());
  for (float v : rgb) EXPECT_EQ(v, 1.f);
  for (float v : depth) EXPECT_EQ(v, 0.f);
}

class VolumeRenderHeadTest : public ::testing::TestWithParam<HeadKind> {};
INSTANTIATE_TEST_SUITE_P(Heads, VolumeRenderHeadTest,
                         ::testing::Values(HeadKind::kPerSample, HeadKind::kDeferred),
                         [](const ::testing::TestParamInfo<HeadKind>& info) {
                           return std::string(HeadKindName(info.param));
                         });

TEST_P(VolumeRenderHeadTest, RenderMatchesTrainStepForward) {
  TensorfConfig c = testing_models::TinyTensorfConfig();
  c.head.kind = GetParam();
  c.density_shift = -1.f;
  TensorfModel model(c);
  model.Initialize({8, 8, 8}, 3);
  std::vector<float> o, d;
  testing_models::RaysFromSphere(50, 5, &o, &d);
  std::vector<float> rgb(150);
  RenderRays(model, 50, o.data(), d.data(), rgb.data(), nullptr);
  // rgb as target; a TrainStep without jitter is not available, so check the loss is small
  // but non-zero (jitter moves the samples by < one step).
  TensorfModel copy = model;
  const TrainStepStats s = TrainStep(copy, 50, o.data(), d.data(), rgb.data(), 7);
  EXPECT_LT(s.mse, 1e-2);
  EXPECT_GT(s.density_samples, 50);
  // The head's rows (the benchmarks' work count): a row per coloured sample, or per coloured ray.
  EXPECT_GT(s.head_rows, 0);
  if (GetParam() == HeadKind::kPerSample) {
    EXPECT_EQ(s.head_rows, s.appearance_samples);
  } else {
    EXPECT_LE(s.head_rows, 50);
    EXPECT_LT(s.head_rows, s.appearance_samples);
  }
}

struct FdSetup {
  TensorfModel model;
  std::vector<float> o, d, target;
  int n;
  float distortion_weight = 0.f;
  std::vector<float> gain;  // per-ray exposure gains (empty: none)
};

FdSetup MakeFdSetup(HeadKind head = HeadKind::kPerSample,
                    DensityActivation activation = DensityActivation::kSoftplus) {
  TensorfConfig c = testing_models::TinyTensorfConfig();
  c.head.kind = head;
  c.density_activation = activation;
  // ReLU: shifted so that few features lie within a finite difference of its kink at 0.
  c.density_shift = activation == DensityActivation::kRelu ? 0.5f : -1.f;
  c.distance_scale = 1.f;
  c.init_scale = 0.4f;
  c.weight_threshold = 0.f;  // no colour-sample switching under perturbation
  FdSetup s{TensorfModel(c), {}, {}, {}, 8, 0.f};
  s.model.Initialize({6, 6, 6}, 12);
  testing_models::RaysFromSphere(s.n, 3, &s.o, &s.d);
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(0.2f, 0.8f);
  s.target.resize(3 * s.n);
  for (auto& v : s.target) v = u(rng);
  return s;
}

double Loss(const FdSetup& s, const TensorfModel& m) {
  TensorfModel copy = m;
  return TrainStep(copy, s.n, s.o.data(), s.d.data(), s.target.data(), 99, s.distortion_weight,
                   s.gain.empty() ? nullptr : s.gain.data())
      .loss;
}

void CheckFd(FdSetup& s, std::vector<float>& params, const std::vector<float>& grads,
             const std::vector<size_t>& idx, float eps, const char* what) {
  int checked = 0;
  for (size_t i : idx) {
    const float v = params[i];
    params[i] = v + eps;
    const double lp = Loss(s, s.model);
    params[i] = v - eps;
    const double lm = Loss(s, s.model);
    params[i] = v;
    const double fd = (lp - lm) / (2 * eps);
    EXPECT_NEAR(grads[i], fd, 2e-6 + 2e-2 * std::fabs(fd)) << what << " entry " << i;
    checked += fd != 0.0;
  }
  EXPECT_GT(checked, static_cast<int>(idx.size()) / 4) << what;
}

void CheckTrainStepGradients(HeadKind head,
                             DensityActivation activation = DensityActivation::kSoftplus) {
  FdSetup s = MakeFdSetup(head, activation);
  s.model.ZeroGrads();
  const TrainStepStats st = TrainStep(s.model, s.n, s.o.data(), s.d.data(), s.target.data(), 99);
  EXPECT_GT(st.density_samples, 40);
  EXPECT_EQ(st.appearance_samples, st.density_samples);  // threshold 0
  EXPECT_GT(st.loss, 1e-3);
  // Every other entry (the check costs two TrainSteps per entry).
  std::vector<size_t> all_d;
  for (size_t i = 0; i < s.model.density().params().size(); i += 2) all_d.push_back(i);
  std::vector<float> dgrad = s.model.density().grads();
  CheckFd(s, s.model.density().params(), dgrad, all_d, 1e-2f, "density");
  std::vector<size_t> all_a;
  for (size_t i = 1; i < s.model.appearance().params().size(); i += 2) all_a.push_back(i);
  std::vector<float> agrad = s.model.appearance().grads();
  CheckFd(s, s.model.appearance().params(), agrad, all_a, 1e-2f, "appearance");
  // Head parameters: directional derivatives (single entries are too ReLU-kinked / small).
  std::vector<float> hgrad = s.model.head().grads();
  std::vector<float>& hp = s.model.head().params();
  const std::vector<float> h0 = hp;
  std::mt19937 rng(17);
  std::normal_distribution<float> nd;
  for (int dir = 0; dir < 4; ++dir) {
    std::vector<float> v(hp.size());
    double norm = 0;
    for (size_t i = 0; i < v.size(); ++i) {
      v[i] = dir == 0 ? hgrad[i] : nd(rng);
      norm += static_cast<double>(v[i]) * v[i];
    }
    double gv = 0;
    for (size_t i = 0; i < v.size(); ++i) {
      v[i] = static_cast<float>(v[i] / std::sqrt(norm));
      gv += static_cast<double>(v[i]) * hgrad[i];
    }
    // Small enough not to cross a ReLU kink of the head: deferred rows are sums of a ray's
    // products, larger than one sample's.
    const float h = 3e-3f;
    for (size_t i = 0; i < v.size(); ++i) hp[i] = h0[i] + h * v[i];
    const double lp = Loss(s, s.model);
    for (size_t i = 0; i < v.size(); ++i) hp[i] = h0[i] - h * v[i];
    const double lm = Loss(s, s.model);
    hp = h0;
    const double fd = (lp - lm) / (2 * h);
    EXPECT_NEAR(gv, fd, 1e-6 + 2e-2 * std::fabs(fd)) << "head direction " << dir;
  }
}

TEST(VolumeRenderTest, TrainStepGradientsMatchFiniteDifferences) {
  CheckTrainStepGradients(HeadKind::kPerSample);
}

// The deferred head: a sample's weight reaches the pixel through the ray's colour weight and its
// share of the summed products, each sample's products through the summed ones.
TEST(VolumeRenderTest, DeferredHeadGradientsMatchFiniteDifferences) {
  CheckTrainStepGradients(HeadKind::kDeferred);
}

// ReLU density (TensoRF's LLFF setting): the gradient passes where the feature is positive and
// stops where it is not.
TEST(VolumeRenderTest, ReluDensityGradientsMatchFiniteDifferences) {
  CheckTrainStepGradients(HeadKind::kDeferred, DensityActivation::kRelu);
  // Every feature below 0: sigma is exactly 0, nothing is coloured, no gradient reaches the grids
  // (softplus would still pass exp(x)).
  TensorfConfig c = testing_models::TinyTensorfConfig();
  c.density_activation = DensityActivation::kRelu;
  c.density_shift = -100.f;
  TensorfModel model(c);
  model.Initialize({6, 6, 6}, 12);
  std::vector<float> o, d;
  testing_models::RaysFromSphere(8, 3, &o, &d);
  const std::vector<float> target(3 * 8, 0.5f);
  model.ZeroGrads();
  const TrainStepStats st = TrainStep(model, 8, o.data(), d.data(), target.data(), 99);
  EXPECT_GT(st.density_samples, 40);
  EXPECT_EQ(st.appearance_samples, 0);
  for (float g : model.density().grads()) ASSERT_EQ(g, 0.f);
}

TEST(VolumeRenderTest, DistortionLossMatchesPairSumAndFiniteDifferences) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int n = 17;
  std::vector<double> w(n), m(n);
  double pos = 0.1;
  for (int i = 0; i < n; ++i) {
    w[i] = u(rng) * 0.3;
    pos += 0.02 + 0.1 * u(rng);
    m[i] = pos;
  }
  m[5] = m[4];  // two samples at one position
  w[9] = 0.0;
  const double delta = 0.05;
  auto pair_sum = [&](const std::vector<double>& ww) {
    double l = 0;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) l += ww[i] * ww[j] * std::fabs(m[i] - m[j]);
      l += delta / 3 * ww[i] * ww[i];
    }
    return l;
  };
  std::vector<double> grad(n);
  const double loss = DistortionLoss(n, w.data(), m.data(), delta, grad.data());
  EXPECT_NEAR(loss, pair_sum(w), 1e-12);
  for (int i = 0; i < n; ++i) {
    std::vector<double> ww = w;
    const double eps = 1e-6;
    ww[i] = w[i] + eps;
    const double lp = pair_sum(ww);
    ww[i] = w[i] - eps;
    const double lm = pair_sum(ww);
    EXPECT_NEAR(grad[i], (lp - lm) / (2 * eps), 1e-7) << "weight " << i;
  }
  // The same total weight in one interval costs less than spread along the ray.
  std::vector<double> one(n, 0.0), spread(n, 0.6 / n);
  one[8] = 0.6;
  EXPECT_LT(DistortionLoss(n, one.data(), m.data(), delta, static_cast<double*>(nullptr)),
            0.2 * DistortionLoss(n, spread.data(), m.data(), delta, static_cast<double*>(nullptr)));
}

TEST(VolumeRenderTest, TrainStepDistortionLossIsTheTracedRaysLoss) {
  FdSetup s = MakeFdSetup();
  s.model.ZeroGrads();
  const float weight = 0.3f;
  const TrainStepStats st =
      TrainStep(s.model, s.n, s.o.data(), s.d.data(), s.target.data(), 99, weight);
  // Positions in units of the ray's sample cap: t / (step * n_samples) differs from them by a
  // constant per ray, which the loss does not see.
  const double unit = 1.0 / (static_cast<double>(s.model.step_size()) * s.model.n_samples());
  double sum = 0;
  for (int r = 0; r < s.n; ++r) {
    const std::vector<RaySampleInfo> samples =
        TraceRay(s.model, &s.o[3 * r], &s.d[3 * r], RayJitter(99, r));
    std::vector<double> w, m;
    for (const RaySampleInfo& x : samples) {
      w.push_back(x.weight);
      m.push_back(x.t * unit);
    }
    sum += DistortionLoss(static_cast<int>(w.size()), w.data(), m.data(), 1.0 / s.model.n_samples(),
                          static_cast<double*>(nullptr));
  }
  EXPECT_GT(st.distortion, 1e-4);
  EXPECT_NEAR(st.distortion, sum / s.n, 1e-4 * st.distortion);
  EXPECT_NEAR(st.loss, st.mse + weight * st.distortion, 1e-9);
}

TEST(VolumeRenderTest, TrainStepDistortionGradientsMatchFiniteDifferences) {
  FdSetup s = MakeFdSetup();
  s.distortion_weight = 0.5f;
  s.model.ZeroGrads();
  const TrainStepStats st =
      TrainStep(s.model, s.n, s.o.data(), s.d.data(), s.target.data(), 99, s.distortion_weight);
  // The term must weigh: at least a tenth of the loss.
  EXPECT_GT(s.distortion_weight * st.distortion, 0.1 * st.loss);
  std::vector<size_t> all_d;
  for (size_t i = 0; i < s.model.density().params().size(); i += 2) all_d.push_back(i);
  std::vector<float> dgrad = s.model.density().grads();
  CheckFd(s, s.model.density().params(), dgrad, all_d, 1e-2f, "density");
}

// Per-ray exposure gains (trainer/train/exposure_codes.h): the gradient with respect to each gain
// and the grids' gradients through the gains, against finite differences of the loss.
TEST(VolumeRenderTest, TrainStepExposureGainGradientsMatchFiniteDifferences) {
  FdSetup s = MakeFdSetup();
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> u(0.7f, 1.4f);
  s.gain.resize(3 * s.n);
  for (auto& g : s.gain) g = u(rng);
  std::vector<float> dl_dgain(3 * s.n, -1.f);
  s.model.ZeroGrads();
  const TrainStepStats st = TrainStep(s.model, s.n, s.o.data(), s.d.data(), s.target.data(), 99,
                                      0.f, s.gain.data(), dl_dgain.data());
  EXPECT_GT(st.loss, 1e-3);
  // The gains change the loss: without them it differs.
  TensorfModel plain = s.model;
  EXPECT_NE(TrainStep(plain, s.n, s.o.data(), s.d.data(), s.target.data(), 99).loss, st.loss);
  int moved = 0;
  for (size_t i = 0; i < s.gain.size(); ++i) {
    const float g0 = s.gain[i], h = 1e-2f;
    s.gain[i] = g0 + h;
    const double lp = Loss(s, s.model);
    s.gain[i] = g0 - h;
    const double lm = Loss(s, s.model);
    s.gain[i] = g0;
    const double fd = (lp - lm) / (2 * h);
    EXPECT_NEAR(dl_dgain[i], fd, 2e-6 + 2e-2 * std::fabs(fd)) << "gain " << i;
    moved += fd != 0.0;
  }
  EXPECT_GT(moved, 3 * s.n / 2);
  std::vector<size_t> some_d, some_a;
  for (size_t i = 0; i < s.model.density().params().size(); i += 3) some_d.push_back(i);
  for (size_t i = 1; i < s.model.appearance().params().size(); i += 3) some_a.push_back(i);
  std::vector<float> dgrad = s.model.density().grads(), agrad = s.model.appearance().grads();
  CheckFd(s, s.model.density().params(), dgrad, some_d, 1e-2f, "density");
  CheckFd(s, s.model.appearance().params(), agrad, some_a, 1e-2f, "appearance");
}

TEST_P(VolumeRenderHeadTest, TrainStepSameGradientsForAnyThreadCount) {
  // Ranks of the trainer's size; more threads than the scatter's six tasks, and more than cores.
  TensorfConfig c = testing_models::TinyTensorfConfig();
  c.head.kind = GetParam();
  c.density_ranks = {16, 16, 16};
  c.app_ranks = {20, 20, 20};
  c.head.num_products = 60;
  c.density_shift = -1.f;
  c.init_scale = 0.4f;
  TensorfModel model(c);
  model.Initialize({9, 8, 7}, 12);
  std::vector<float> o, d;
  testing_models::RaysFromSphere(300, 8, &o, &d);
  const std::vector<float> target(900, 0.5f);
  const int saved = omp_get_max_threads();
  TensorfModel a = model;
  a.ZeroGrads();
  omp_set_num_threads(1);
  const TrainStepStats sa = TrainStep(a, 300, o.data(), d.data(), target.data(), 5);
  ASSERT_GT(sa.appearance_samples, 1000);
  for (int threads : {2, 3, 8, 24}) {
    TensorfModel b = model;
    b.ZeroGrads();
    omp_set_num_threads(threads);
    const TrainStepStats sb = TrainStep(b, 300, o.data(), d.data(), target.data(), 5);
    EXPECT_NEAR(sa.loss, sb.loss, 1e-9) << threads << " threads";
    EXPECT_EQ(sa.density_samples, sb.density_samples);
    // Each (grid, mode) is scattered by one task in ray order and the head sums its weight
    // gradients in fixed runs of chunks: the same bits for any thread count.
    EXPECT_EQ(a.density().grads(), b.density().grads()) << threads << " threads";
    EXPECT_EQ(a.appearance().grads(), b.appearance().grads()) << threads << " threads";
    EXPECT_EQ(a.head().grads(), b.head().grads()) << threads << " threads";
  }
  omp_set_num_threads(saved);
}

TEST_P(VolumeRenderHeadTest, HeadChunkingAndMaskKeepResults) {
  TensorfConfig c = testing_models::TinyTensorfConfig();
  c.head.kind = GetParam();
  c.density_shift = -2.f;
  TensorfConfig cc = c;
  cc.head_chunk_rows = 7;  // many chunks, some rays larger than a chunk
  TensorfModel a(c), b(cc);
  a.Initialize({10, 10, 10}, 8);
  b.Initialize({10, 10, 10}, 8);
  // Mask: occupied for x < 0 only (half of the box).
  std::vector<uint8_t> occ(10 * 10 * 10, 0);
  for (int z = 0; z < 10; ++z)
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 5; ++x) occ[(z * 10 + y) * 10 + x] = 1;
  for (TensorfModel* m : {&a, &b}) m->SetAlphaMask(AlphaMask(m->aabb(), {10, 10, 10}, occ));
  std::vector<float> o, d;
  testing_models::RaysFromSphere(150, 12, &o, &d);
  std::vector<float> target(450, 0.4f);
  a.ZeroGrads();
  b.ZeroGrads();
  const TrainStepStats sa = TrainStep(a, 150, o.data(), d.data(), target.data(), 3);
  const TrainStepStats sb = TrainStep(b, 150, o.data(), d.data(), target.data(), 3);
  EXPECT_GT(sa.appearance_samples, 100);
  EXPECT_EQ(sa.density_samples, sb.density_samples);
  EXPECT_EQ(sa.appearance_samples, sb.appearance_samples);
  EXPECT_NEAR(sa.loss, sb.loss, 1e-7);
  for (size_t i = 0; i < a.density().grads().size(); ++i)
    ASSERT_NEAR(a.density().grads()[i], b.density().grads()[i],
                1e-7 + 1e-4 * std::fabs(a.density().grads()[i]));
  for (size_t i = 0; i < a.appearance().grads().size(); ++i)
    ASSERT_NEAR(a.appearance().grads()[i], b.appearance().grads()[i],
                1e-7 + 1e-4 * std::fabs(a.appearance().grads()[i]));
  for (size_t i = 0; i < a.head().grads().size(); ++i)
    ASSERT_NEAR(a.head().grads()[i], b.head().grads()[i],
                1e-6 + 1e-3 * std::fabs(a.head().grads()[i]));
  // Masked-out samples are skipped: every traced sample lies in an occupied mask cell.
  for (int r = 0; r < 150; ++r)
    for (const auto& smp : TraceRay(a, &o[3 * r], &d[3 * r], RayJitter(3, r))) {
      const float x[3] = {o[3 * r] + d[3 * r] * smp.t, o[3 * r + 1] + d[3 * r + 1] * smp.t,
                          o[3 * r + 2] + d[3 * r + 2] * smp.t};
      ASSERT_TRUE(a.alpha_mask()->Occupied(x));
      ASSERT_LT(x[0], 0.23f);  // occupied up to vertex 4 (x = -0.111) plus one cell of support
    }
  TensorfModel nomask = a;
  nomask.ClearAlphaMask();
  const TrainStepStats sn = TrainStep(nomask, 150, o.data(), d.data(), target.data(), 3);
  EXPECT_LT(sa.density_samples, 0.8 * sn.density_samples);
}

TEST(VolumeRenderTest, StatsCountTracedSamples) {
  TensorfConfig c = testing_models::TinyTensorfConfig();
  c.density_shift = 0.f;
  TensorfModel model(c);
  model.Initialize({10, 10, 10}, 6);
  std::vector<float> o, d;
  testing_models::RaysFromSphere(40, 9, &o, &d);
  std::vector<float> target(120, 0.3f);
  TensorfModel copy = model;
  const TrainStepStats st = TrainStep(copy, 40, o.data(), d.data(), target.data(), 123);
  long dens = 0, app = 0;
  for (int r = 0; r < 40; ++r) {
    const auto samples = TraceRay(model, &o[3 * r], &d[3 * r], RayJitter(123, r));
    dens += samples.size();
    for (const auto& s : samples) app += s.colour;
  }
  EXPECT_EQ(st.density_samples, dens);
  EXPECT_EQ(st.appearance_samples, app);
  EXPECT_GT(app, 0);
  EXPECT_LT(app, dens);
  EXPECT_EQ(st.rays, 40);
}

// Relative L2 norm of a - b over the norm of a.
double RelDiff(const std::vector<float>& a, const std::vector<float>& b) {
  double num = 0, den = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    num += (static_cast<double>(a[i]) - b[i]) * (static_cast<double>(a[i]) - b[i]);
    den += static_cast<double>(a[i]) * a[i];
  }
  return std::sqrt(num / den);
}

TEST(VolumeRenderTest, EarlyStopChangesGradientsNegligibly) {
  // An opaque blob in empty space (the default density shift): rays through the blob saturate,
  // the others see almost nothing.
  TensorfConfig c = testing_models::TinyTensorfConfig();
  TensorfConfig ce = c;
  ce.early_stop_transmittance = 1e-4f;
  TensorfModel exact(c), early(ce);
  for (TensorfModel* m : {&exact, &early}) {
    m->Initialize({16, 16, 16}, 6);
    VmGrid& g = m->density();
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) {
        const float dx = (x - 7.5f) / 7.5f, dy = (y - 7.5f) / 7.5f;
        g.PlaneAt(0, y, x, 0) = 3.5f * std::max(0.f, 1.f - 2.f * (dx * dx + dy * dy));
      }
    for (int z = 0; z < 16; ++z) {
      const float dz = (z - 7.5f) / 7.5f;
      g.LineAt(0, z, 0) = 4.f * std::max(0.f, 1.f - 2.f * dz * dz);
    }
  }
  std::vector<float> o, d;
  testing_models::RaysFromSphere(400, 10, &o, &d);
  std::vector<float> target(1200);
  for (size_t i = 0; i < target.size(); ++i) target[i] = 0.2f + 0.6f * ((i * 7) % 11) / 10.f;
  exact.ZeroGrads();
  early.ZeroGrads();
  const TrainStepStats se = TrainStep(exact, 400, o.data(), d.data(), target.data(), 1);
  const TrainStepStats s2 = TrainStep(early, 400, o.data(), d.data(), target.data(), 1);
  EXPECT_LT(s2.density_samples, se.density_samples);
  EXPECT_EQ(s2.appearance_samples, se.appearance_samples);
  EXPECT_NEAR(s2.loss, se.loss, 2e-4 * se.loss + 1e-6);
  const double dd = RelDiff(exact.density().grads(), early.density().grads());
  const double da = RelDiff(exact.appearance().grads(), early.appearance().grads());
  const double dh = RelDiff(exact.head().grads(), early.head().grads());
  std::printf("early stop: samples %ld -> %ld, rel. grad diff density %.2e app %.2e head %.2e\n",
              se.density_samples, s2.density_samples, dd, da, dh);
  EXPECT_LT(dd, 1e-2);
  EXPECT_LT(da, 1e-3);
  EXPECT_LT(dh, 1e-3);
}

TEST_P(VolumeRenderHeadTest, AdamStepsReduceLoss) {
  TensorfConfig c = testing_models::TinyTensorfConfig();
  c.head.kind = GetParam();
  c.head.hidden = 32;
  TensorfModel model(c);
  model.Initialize({12, 12, 12}, 21);
  const int n = 256;
  std::vector<float> o, d;
  testing_models::RaysFromSphere(n, 11, &o, &d);
  std::vector<float> target(3 * n);
  for (int r = 0; r < n; ++r) {  // colour depends on the direction: a smooth "scene"
    target[3 * r + 0] = 0.5f + 0.4f * d[3 * r + 0];
    target[3 * r + 1] = 0.2f;
    target[3 * r + 2] = 0.5f - 0.4f * d[3 * r + 2];
  }
  Adam adam_d(model.density().params().size(), AdamConfig());
  Adam adam_a(model.appearance().params().size(), AdamConfig());
  Adam adam_h(model.head().params().size(), AdamConfig());
  double first = 0, last = 0;
  for (int it = 0; it < 60; ++it) {
    model.ZeroGrads();
    const TrainStepStats st = TrainStep(model, n, o.data(), d.data(), target.data(), it);
    if (it == 0) first = st.loss;
    last = st.loss;
    adam_d.Step(model.density().params().data(), model.density().grads().data(),
                model.density().params().size(), 0.02f);
    adam_a.Step(model.appearance().params().data(), model.appearance().grads().data(),
                model.appearance().params().size(), 0.02f);
    adam_h.Step(model.head().params().data(), model.head().grads().data(),
                model.head().params().size(), 1e-3f);
  }
  EXPECT_LT(last, 0.5 * first) << first << " -> " << last;
}

// Trained with the distortion loss, the same fit ends with its rays' weight in shorter stretches
// (a smaller distortion) than trained without it, at a colour error of the same order.
TEST(VolumeRenderTest, DistortionLossConcentratesTheWeights) {
  TensorfConfig c = testing_models::TinyTensorfConfig();
  c.head.hidden = 32;
  c.init_scale = 0.3f;
  c.density_shift = -2.f;  // a foggy start: weight spread along every ray
  const int n = 256;
  std::vector<float> o, d;
  testing_models::RaysFromSphere(n, 11, &o, &d);
  std::vector<float> target(3 * n);
  for (int r = 0; r < n; ++r) {
    target[3 * r + 0] = 0.5f + 0.4f * d[3 * r + 0];
    target[3 * r + 1] = 0.2f;
    target[3 * r + 2] = 0.5f - 0.4f * d[3 * r + 2];
  }
  auto train = [&](float weight) {
    TensorfModel model(c);
    model.Initialize({12, 12, 12}, 21);
    Adam adam_d(model.density().params().size(), AdamConfig());
    Adam adam_a(model.appearance().params().size(), AdamConfig());
    Adam adam_h(model.head().params().size(), AdamConfig());
    TrainStepStats st;
    for (int it = 0; it < 80; ++it) {
      model.ZeroGrads();
      st = TrainStep(model, n, o.data(), d.data(), target.data(), it, weight);
      adam_d.Step(model.density().params().data(), model.density().grads().data(),
                  model.density().params().size(), 0.02f);
      adam_a.Step(model.appearance().params().data(), model.appearance().grads().data(),
                  model.appearance().params().size(), 0.02f);
      adam_h.Step(model.head().params().data(), model.head().grads().data(),
                  model.head().params().size(), 1e-3f);
    }
    // The distortion of the trained model, measured the same way for both.
    model.ZeroGrads();
    return TrainStep(model, n, o.data(), d.data(), target.data(), 1000, 1e-6f);
  };
  const TrainStepStats plain = train(0.f), regularized = train(0.05f);
  std::printf("distortion %.3g -> %.3g, mse %.3g -> %.3g\n", plain.distortion,
              regularized.distortion, plain.mse, regularized.mse);
  EXPECT_LT(regularized.distortion, 0.5 * plain.distortion)
      << plain.distortion << " -> " << regularized.distortion;
  EXPECT_LT(regularized.mse, 4 * plain.mse + 1e-3) << plain.mse << " -> " << regularized.mse;
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
