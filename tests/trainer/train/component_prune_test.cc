// Component pruning: removing a component from the grids, the head and the optimizers renders
// exactly what zeroing it did, and the drop test removes what costs more than it gives.
#include "trainer/train/component_prune.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "format/mlp_coder.h"
#include "tests/common/small_model.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/quant_aware.h"
#include "trainer/rate/rate_objective.h"

namespace ecrf {
namespace trainer {
namespace {

using testing_models::DenseSmallModel;
using testing_models::RaysFromSphere;
using testing_models::SmallRateBlocks;

constexpr int kRays = 512;

struct Rays {
  std::vector<float> o, d;
  Rays() { RaysFromSphere(kRays, 11, &o, &d); }
};

std::vector<float> Render(const TensorfModel& model, const Rays& rays) {
  std::vector<float> rgb(size_t(kRays) * 3);
  RenderRays(model, kRays, rays.o.data(), rays.d.data(), rgb.data(), nullptr);
  return rgb;
}

void ZeroLineChannel(TensorfModel* model, int g, int m, int r) {
  VmGrid& grid = g == 0 ? model->density() : model->appearance();
  const int rank = grid.ranks()[m];
  for (size_t i = 0; i < grid.line_size(m) / size_t(rank); ++i) grid.line(m)[i * rank + r] = 0.f;
}

RateState ActiveRate(const TensorfModel& model) {
  TrainOptions o;
  const encoder::RateConfig b = SmallRateBlocks();
  for (int a = 0; a < 3; ++a) {
    o.plane_block[a] = b.plane_block[a];
    o.line_block[a] = b.line_block[a];
  }
  o.quant_step_scale = 1.f;
  RateState rate;
  rate.Activate(model, o);
  return rate;
}

// A tensor nearly dead when the rate terms switch on gets no step finer than 1/64 of its
// siblings' largest (rate_state.h); live tensors keep their own, a dead one its placeholder.
TEST(RateSteps, ANearlyDeadTensorGetsNoStepFinerThanItsSiblingsOverTheFloorRatio) {
  TensorfModel model = DenseSmallModel();
  const std::vector<float> own = ActiveRate(model).steps;
  VmGrid& density = model.density();
  for (size_t i = 0; i < density.plane_size(2); ++i) density.plane(2)[i] *= 1e-5f;
  const std::vector<float> floored = ActiveRate(model).steps;
  ASSERT_EQ(floored.size(), own.size());
  const float largest = std::max(own[0], own[1]);
  EXPECT_LT(own[2] * 1e-5f, largest / kStepFloorRatio);  // what the peak alone would give
  EXPECT_FLOAT_EQ(floored[2], largest / kStepFloorRatio);
  for (size_t t = 0; t < own.size(); ++t) {
    if (t != 2) EXPECT_EQ(floored[t], own[t]) << t;
  }
  std::vector<float> steps = {1.f, 1e-4f, 0.5f, 2.f, 2.f, 2.f};
  FloorNearlyDeadSteps({3.f, 0.f, 1.f, 1.f, 1.f, 1.f}, &steps);
  EXPECT_EQ(steps, (std::vector<float>{1.f, 1e-4f, 0.5f, 2.f, 2.f, 2.f}));  // peak 0: untouched
  steps = {1.f, 1e-4f, 0.5f};
  FloorNearlyDeadSteps({3.f, 1e-5f, 1.f}, &steps);
  EXPECT_EQ(steps, (std::vector<float>{1.f, 1.f / 64, 0.5f}));
}

TEST(KeepComponents, RendersWhatZeroingTheComponentRendered) {
  const Rays rays;
  for (int g = 0; g < 2; ++g) {
    TensorfModel zeroed = DenseSmallModel();
    ZeroLineChannel(&zeroed, g, 1, 2);
    TensorfModel removed = DenseSmallModel();
    std::array<std::vector<uint8_t>, 3> keep = {{{1, 1, 1, 1}, {1, 1, 0, 1}, {1, 1, 1, 1}}};
    removed.KeepComponents(g, keep);
    const std::array<int, 3> ranks = {4, 3, 4};
    EXPECT_EQ((g == 0 ? removed.density() : removed.appearance()).ranks(), ranks);
    EXPECT_EQ((g == 0 ? removed.config().density_ranks : removed.config().app_ranks), ranks);
    EXPECT_EQ(removed.head().config().num_products, g == 1 ? 11 : 12);
    EXPECT_EQ(removed.config().head.num_products, g == 1 ? 11 : 12);
    const std::vector<float> a = Render(zeroed, rays), b = Render(removed, rays);
    double max_diff = 0.0, spread = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
      max_diff = std::max(max_diff, double(std::fabs(a[i] - b[i])));
      spread = std::max(spread, double(std::fabs(a[i] - a[0])));
    }
    EXPECT_LT(max_diff, 1e-5) << "grid " << g;
    EXPECT_GT(spread, 0.05) << "the renders must depend on the model";
  }
}

TEST(KeepComponents, KeptIndicesPickTheValuesThatStay) {
  TensorfModel model = DenseSmallModel();
  const std::array<std::vector<uint8_t>, 3> keep = {{{0, 1, 1, 1}, {1, 1, 1, 1}, {1, 0, 0, 1}}};
  for (int g = 0; g < 2; ++g) {
    VmGrid& grid = g == 0 ? model.density() : model.appearance();
    std::vector<float>& p = grid.params();
    for (size_t k = 0; k < p.size(); ++k) p[k] = float(k);
  }
  std::vector<float>& head = model.head().params();
  for (size_t k = 0; k < head.size(); ++k) head[k] = float(k);
  std::vector<uint8_t> products;
  for (const auto& k : keep) products.insert(products.end(), k.begin(), k.end());
  const std::vector<size_t> grid_idx = model.appearance().KeptIndices(keep);
  const std::vector<size_t> head_idx = model.head().KeptIndices(products);
  // An optimizer whose moments hold each value's index follows the same selection.
  Optimizers opt;
  opt.Reset(model);
  for (size_t k = 0; k < opt.appearance.size(); ++k) opt.appearance.first_moment()[k] = float(k);
  for (size_t k = 0; k < opt.head.size(); ++k) opt.head.second_moment()[k] = float(k);
  PruneDecision d;
  for (int m = 0; m < 3; ++m) d.keep[0][m].assign(4, 1);
  d.keep[1] = keep;
  PruneComponents(d, &model, &opt);
  ASSERT_EQ(model.appearance().params().size(), grid_idx.size());
  ASSERT_EQ(model.appearance().params().size(), 16u * 16 * 9 + 16u * 9);
  for (size_t i = 0; i < grid_idx.size(); ++i) {
    ASSERT_EQ(model.appearance().params()[i], float(grid_idx[i]));
    ASSERT_EQ(opt.appearance.first_moment()[i], float(grid_idx[i]));
  }
  ASSERT_EQ(model.head().params().size(), head_idx.size());
  for (size_t i = 0; i < head_idx.size(); ++i) {
    ASSERT_EQ(model.head().params()[i], float(head_idx[i]));
    ASSERT_EQ(opt.head.second_moment()[i], float(head_idx[i]));
  }
  // Plane 0 of appearance kept channels 1..3 of 4: its first vertex holds values 1, 2, 3.
  EXPECT_EQ(model.appearance().plane(0)[0], 1.f);
  EXPECT_EQ(model.appearance().plane(0)[2], 3.f);
  EXPECT_EQ(model.density().params().size(), opt.density.size());
  EXPECT_THROW(model.KeepComponents(0, {{{0, 0, 0, 0}, {1, 1, 1, 1}, {1, 1, 1, 1}}}),
               std::invalid_argument);
}

TEST(TestComponents, RemovesTheComponentTheTargetLacks) {
  const Rays rays;
  TensorfModel model = DenseSmallModel();
  TensorfModel target_model = model;
  ZeroLineChannel(&target_model, 1, 2, 1);  // appearance mode 2, component 1
  const std::vector<float> target = Render(target_model, rays);
  const RateState rate = ActiveRate(model);
  const double lambda_e = 1e-12;  // bits almost free: a component goes when it lowers the MSE
  const PruneDecision d = TestComponents(model, rate, lambda_e, kRays, rays.o.data(), rays.d.data(),
                                         target.data(), 0.5);
  ASSERT_EQ(d.tests.size(), 24u);
  ASSERT_GT(d.mse, 1e-5);
  int lacked_drops = 0;
  for (const ComponentTest& t : d.tests) {
    EXPECT_GT(t.bits, 0.0);
    if (t.grid == 1 && t.mode == 2 && t.component == 1) {
      EXPECT_NEAR(t.dmse, -d.mse, 1e-9);  // without it the model renders the target
      lacked_drops += t.drop;
    }
    if (t.drop) EXPECT_LT(t.dmse, lambda_e * t.bits);
  }
  EXPECT_EQ(lacked_drops, 1);
  // In a dense medium some density components lower the error too; the rest stay.
  EXPECT_GE(d.dropped, 1);
  EXPECT_LT(d.dropped, 12);
  Optimizers opt;
  opt.Reset(model);
  PruneComponents(d, &model, &opt);
  EXPECT_EQ(model.appearance().ranks()[2], 3);
  EXPECT_LT(RenderMse(model, kRays, rays.o.data(), rays.d.data(), target.data()), 0.5 * d.mse);
}

// With exposure gains the test judges each ray's render at its image's gain, before the clamp, as
// the training loss does: against images that are the model's render at per-ray gains, the
// model's error is nil with the gains and not without them.
TEST(TestComponents, JudgesTheRenderAtEachRaysExposureGain) {
  const TensorfModel model = DenseSmallModel();
  const Rays rays;
  std::vector<float> gains(size_t(kRays) * 3), target(size_t(kRays) * 3);
  for (size_t i = 0; i < gains.size(); ++i) gains[i] = 0.8f + 0.04f * float((i * 7) % 11);
  RenderRays(model, kRays, rays.o.data(), rays.d.data(), target.data(), nullptr, gains.data());
  const std::vector<float> plain = Render(model, rays);
  int unclamped = 0;
  for (size_t i = 0; i < plain.size(); ++i) {
    EXPECT_EQ(target[i], std::min(std::max(gains[i] * plain[i], 0.f), 1.f)) << i;
    if (gains[i] * plain[i] < 1.f && gains[i] != 1.f) ++unclamped;
  }
  EXPECT_GT(unclamped, kRays / 4);  // the gains change most pixels
  const RateState rate = ActiveRate(model);
  const PruneDecision with = TestComponents(model, rate, 0.0, kRays, rays.o.data(), rays.d.data(),
                                            target.data(), 0.5, gains.data());
  const PruneDecision without =
      TestComponents(model, rate, 0.0, kRays, rays.o.data(), rays.d.data(), target.data(), 0.5);
  EXPECT_EQ(with.mse, 0.0);
  EXPECT_GT(without.mse, 1e-4);
  for (const ComponentTest& t : with.tests) EXPECT_GE(t.dmse, 0.0);  // from a perfect fit
  const HiddenDecision hidden = TestHiddenUnits(model, 15, 0.0, kRays, rays.o.data(), rays.d.data(),
                                                target.data(), 0.5, gains.data());
  EXPECT_EQ(hidden.mse, 0.0);
}

TEST(TestComponents, BitsAreTheRateOfTheModeWithoutTheComponent) {
  const Rays rays;
  const TensorfModel model = DenseSmallModel();
  const RateState rate = ActiveRate(model);
  const std::vector<float> own = Render(model, rays);
  const PruneDecision d =
      TestComponents(model, rate, 0.0, kRays, rays.o.data(), rays.d.data(), own.data(), 1.0);
  // The model renders its own colours: every removal costs MSE, none pays at lambda_e 0.
  EXPECT_EQ(d.dropped, 0);
  EXPECT_DOUBLE_EQ(d.mse, 0.0);
  const ComponentTest& t = d.tests[4 + 3];  // density mode 1, component 3
  ASSERT_EQ(t.grid, 0);
  ASSERT_EQ(t.mode, 1);
  ASSERT_EQ(t.component, 3);
  VmGrid reduced = model.density();
  reduced.KeepComponents({{{1, 1, 1, 1}, {1, 1, 1, 0}, {1, 1, 1, 1}}});
  auto bits = [&](const VmGrid& g) {
    return EvaluateTensorBits(g, 1, rate.steps[1], 1, rate.config, rate.entropy) +
           EvaluateTensorBits(g, 4, rate.steps[4], 4, rate.config, rate.entropy);
  };
  EXPECT_NEAR(t.bits, bits(model.density()) - bits(reduced), 1e-6 * bits(model.density()));
}

TEST(TestComponents, DropsThatPayAloneButNotTogetherAreHalved) {
  const Rays rays;
  TensorfModel model = DenseSmallModel();
  // Appearance mode 0: components 0 and 1 the same weak product with the same basis column, so
  // that removing both changes the features twice as much as removing one (four times the MSE).
  VmGrid& app = model.appearance();
  const int rank = app.ranks()[0];
  for (size_t i = 0; i < app.plane_size(0) / rank; ++i)
    app.plane(0)[i * rank + 1] = app.plane(0)[i * rank];
  for (size_t i = 0; i < app.line_size(0) / rank; ++i) {
    app.line(0)[i * rank] *= 0.05f;
    app.line(0)[i * rank + 1] = app.line(0)[i * rank];
  }
  AppearanceHead& head = model.head();
  const int p = head.config().num_products;
  for (int f = 0; f < head.config().feature_dim; ++f) {
    float* basis = head.params().data() + head.basis_offset() + size_t(f) * p;
    basis[1] = basis[0];
  }
  const std::vector<float> own = Render(model, rays);
  const RateState rate = ActiveRate(model);
  const PruneDecision probe =
      TestComponents(model, rate, 0.0, kRays, rays.o.data(), rays.d.data(), own.data(), 0.5);
  const ComponentTest& c0 = probe.tests[12];  // appearance mode 0, component 0
  const ComponentTest& c1 = probe.tests[13];
  ASSERT_EQ(c0.grid, 1);
  ASSERT_EQ(c0.mode, 0);
  ASSERT_EQ(c1.component, 1);
  ASSERT_GT(c0.dmse, 0.0);
  ASSERT_NEAR(c0.dmse, c1.dmse, 1e-3 * c0.dmse);
  // Each pays alone at this lambda_e; the two together (about 4x the MSE for 2x the bits) do not.
  const double lambda_e = 1.2 * std::max(c0.dmse / c0.bits, c1.dmse / c1.bits);
  const PruneDecision d =
      TestComponents(model, rate, lambda_e, kRays, rays.o.data(), rays.d.data(), own.data(), 0.5);
  EXPECT_EQ(d.keep[1][0][0] + d.keep[1][0][1], 1);
  EXPECT_EQ(d.keep[1][0][2] + d.keep[1][0][3], 2);
  TensorfModel both = model;
  ZeroLineChannel(&both, 1, 0, 0);
  ZeroLineChannel(&both, 1, 0, 1);
  const double joint = RenderMse(both, kRays, rays.o.data(), rays.d.data(), own.data());
  EXPECT_GT(joint, lambda_e * (c0.bits + c1.bits));
}

TEST(TestComponents, DropsAtMostTheShareAndNeverAModesLastComponent) {
  const Rays rays;
  const TensorfModel model = DenseSmallModel();
  const RateState rate = ActiveRate(model);
  const std::vector<float> own = Render(model, rays);
  // Bits so dear that every component is worth dropping alone.
  for (const double share : {0.25, 0.5, 1.0}) {
    const PruneDecision d =
        TestComponents(model, rate, 1e3, kRays, rays.o.data(), rays.d.data(), own.data(), share);
    for (int g = 0; g < 2; ++g) {
      for (int m = 0; m < 3; ++m) {
        int kept = 0;
        for (uint8_t k : d.keep[g][m]) kept += k;
        EXPECT_GE(kept, 1);
        EXPECT_GE(kept, 4 - int(std::floor(share * 4))) << "share " << share;
        EXPECT_EQ(kept, share == 1.0 ? 1 : 4 - int(std::floor(share * 4))) << "share " << share;
      }
    }
  }
  EXPECT_THROW(
      TestComponents(model, RateState(), 1.0, kRays, rays.o.data(), rays.d.data(), own.data(), 0.5),
      std::invalid_argument);
}

// Zeroes the weights and bias of hidden unit u of layer 1 or 2: its output is then 0.
void ZeroHiddenUnit(TensorfModel* model, int layer, int u) {
  AppearanceHead& head = model->head();
  const int width = layer == 1 ? head.mlp_input_dim() : head.config().hidden;
  float* p = head.params().data();
  float* w = p + (layer == 1 ? head.w1_offset() : head.w2_offset()) + size_t(u) * width;
  std::fill(w, w + width, 0.f);
  p[(layer == 1 ? head.b1_offset() : head.b2_offset()) + u] = 0.f;
}

TEST(KeepHidden, RendersWhatZeroingTheUnitsRendered) {
  const Rays rays;
  TensorfModel zeroed = DenseSmallModel();
  ZeroHiddenUnit(&zeroed, 1, 3);
  ZeroHiddenUnit(&zeroed, 1, 9);
  ZeroHiddenUnit(&zeroed, 2, 0);
  ZeroHiddenUnit(&zeroed, 2, 15);
  TensorfModel removed = DenseSmallModel();
  std::vector<uint8_t> keep1(16, 1), keep2(16, 1);
  keep1[3] = keep1[9] = keep2[0] = keep2[15] = 0;
  const size_t before = removed.head().params().size();
  removed.KeepHidden(keep1, keep2);
  EXPECT_EQ(removed.head().config().hidden, 14);
  EXPECT_EQ(removed.config().head.hidden, 14);
  const int in = removed.head().mlp_input_dim();
  EXPECT_EQ(before - removed.head().params().size(),
            size_t(2 * (in + 1) + 16 * 16 - 14 * 14 + 2 * (1 + 3)));
  const std::vector<float> a = Render(zeroed, rays), b = Render(removed, rays);
  for (size_t i = 0; i < a.size(); ++i) ASSERT_NEAR(a[i], b[i], 1e-5);
  EXPECT_THROW(removed.KeepHidden(std::vector<uint8_t>(14, 1), std::vector<uint8_t>(14, 0)),
               std::invalid_argument);
  keep1.assign(14, 1);
  keep1[2] = 0;
  EXPECT_THROW(removed.KeepHidden(keep1, std::vector<uint8_t>(14, 1)), std::invalid_argument);
}

TEST(TestHiddenUnits, RemovesTheUnitTheTargetLacksWhenItPays) {
  const Rays rays;
  TensorfModel model = DenseSmallModel();
  TensorfModel target_model = model;
  ZeroHiddenUnit(&target_model, 1, 5);
  const std::vector<float> target = Render(target_model, rays);
  const HiddenDecision d =
      TestHiddenUnits(model, 15, 1e-12, kRays, rays.o.data(), rays.d.data(), target.data(), 0.25);
  ASSERT_EQ(d.dmse1.size(), 16u);
  ASSERT_GT(d.mse, 1e-6);
  EXPECT_NEAR(d.dmse1[5], -d.mse, 1e-9);  // without it the model renders the target
  EXPECT_GE(d.dropped, 1);
  EXPECT_LE(d.dropped, 4);
  EXPECT_EQ(d.keep1[5], 0);
  EXPECT_GT(d.bits, 0.0);
  // What the test measured jointly (the units zeroed) is what the smaller head renders.
  TensorfModel zeroed = model;
  for (int u = 0; u < 16; ++u) {
    if (!d.keep1[u]) ZeroHiddenUnit(&zeroed, 1, u);
    if (!d.keep2[u]) ZeroHiddenUnit(&zeroed, 2, u);
  }
  const double joint = RenderMse(zeroed, kRays, rays.o.data(), rays.d.data(), target.data());
  EXPECT_LT(joint, d.mse);  // bits almost free: it pays only if the MSE falls
  Optimizers opt;
  opt.Reset(model);
  PruneHidden(d, &model, &opt);
  EXPECT_EQ(model.head().config().hidden, 16 - d.dropped);
  EXPECT_EQ(opt.head.size(), model.head().params().size());
  EXPECT_NEAR(RenderMse(model, kRays, rays.o.data(), rays.d.data(), target.data()), joint, 1e-7);
}

// One hidden layer: a unit is its W1 row, b1 entry and W3 column, judged once.
TEST(TestHiddenUnits, OneHiddenLayerRemovesTheUnitTheTargetLacks) {
  const Rays rays;
  TensorfModel model = DenseSmallModel(1);
  TensorfModel target_model = model;
  ZeroHiddenUnit(&target_model, 1, 7);
  const std::vector<float> target = Render(target_model, rays);
  const HiddenDecision d =
      TestHiddenUnits(model, 15, 1e-12, kRays, rays.o.data(), rays.d.data(), target.data(), 0.25);
  EXPECT_NEAR(d.dmse1[7], -d.mse, 1e-9);
  EXPECT_GE(d.dropped, 1);
  EXPECT_EQ(d.keep1[7], 0);
  EXPECT_EQ(d.keep1, d.keep2);
  TensorfModel zeroed = model;
  for (int u = 0; u < 16; ++u) {
    if (!d.keep1[u]) ZeroHiddenUnit(&zeroed, 1, u);
  }
  const double joint = RenderMse(zeroed, kRays, rays.o.data(), rays.d.data(), target.data());
  Optimizers opt;
  opt.Reset(model);
  const size_t before = model.head().params().size();
  PruneHidden(d, &model, &opt);
  EXPECT_EQ(before - model.head().params().size(),
            size_t(d.dropped) * (model.head().mlp_input_dim() + 1 + 3));
  EXPECT_EQ(opt.head.size(), model.head().params().size());
  EXPECT_NEAR(RenderMse(model, kRays, rays.o.data(), rays.d.data(), target.data()), joint, 1e-7);
}

TEST(TestHiddenUnits, DropsTheShareWhenBitsAreDearAndNothingWhenTheyAreFree) {
  const Rays rays;
  const TensorfModel model = DenseSmallModel();
  const std::vector<float> own = Render(model, rays);
  const HiddenDecision dear =
      TestHiddenUnits(model, 15, 1e3, kRays, rays.o.data(), rays.d.data(), own.data(), 0.5);
  EXPECT_EQ(dear.dropped, 8);
  AppearanceHead smaller = model.head();
  smaller.KeepHidden(dear.keep1, dear.keep2);
  const auto head_bits = [](const AppearanceHead& h) {
    return 8.0 *
           EncodeQuantizedMlp(HeadMlpLayout(h.config()), h.params().data(), 15, nullptr).size();
  };
  EXPECT_DOUBLE_EQ(dear.bits, head_bits(model.head()) - head_bits(smaller));
  const HiddenDecision free_bits =
      TestHiddenUnits(model, 0, 0.0, kRays, rays.o.data(), rays.d.data(), own.data(), 0.5);
  EXPECT_EQ(free_bits.dropped, 0);
  for (double v : free_bits.dmse1) EXPECT_GE(v, 0.0);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
