#include "trainer/train/component_prune.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "format/mlp_coder.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/quant_aware.h"
#include "trainer/rate/rate_objective.h"

namespace ecrf {
namespace trainer {
namespace {

const VmGrid& GridOf(const TensorfModel& model, int g) {
  return g == 0 ? model.density() : model.appearance();
}
VmGrid& GridOf(TensorfModel& model, int g) { return g == 0 ? model.density() : model.appearance(); }

// Estimated bits of plane m and line m of grid g.
double ModeBits(const VmGrid& grid, int g, int m, const RateState& rate) {
  double bits = 0.0;
  for (const int t : {m, 3 + m}) {
    const int ti = g * encoder::kTensorsPerGrid + t;
    bits += EvaluateTensorBits(grid, t, rate.steps[ti], ti, rate.config, rate.entropy);
  }
  return bits;
}

// Bits of the head as the stream codes it.
double HeadBits(const AppearanceHead& head, int mlp_levels) {
  if (mlp_levels <= 0) return 16.0 * double(head.params().size());
  return 8.0 * double(EncodeQuantizedMlp(HeadMlpLayout(head.config()), head.params().data(),
                                         mlp_levels, nullptr)
                          .size());
}

// Zeroes (or restores from `saved`) the weights and bias of hidden unit `unit` of layer 1 or 2.
void SetHiddenUnit(AppearanceHead* head, int layer, int unit, std::vector<float>* saved,
                   bool restore) {
  const int h = head->config().hidden;
  const int width = layer == 1 ? head->mlp_input_dim() : h;
  float* w = head->params().data() + (layer == 1 ? head->w1_offset() : head->w2_offset()) +
             size_t(unit) * width;
  float* b = head->params().data() + (layer == 1 ? head->b1_offset() : head->b2_offset()) + unit;
  if (!restore) {
    saved->assign(w, w + width);
    saved->push_back(*b);
    std::fill(w, w + width, 0.f);
    *b = 0.f;
  } else {
    std::copy(saved->begin(), saved->begin() + width, w);
    *b = saved->back();
  }
}

}  // namespace

HiddenDecision TestHiddenUnits(const TensorfModel& model, int mlp_levels, double lambda_e, int n,
                               const float* origins, const float* dirs, const float* rgb,
                               double max_share, const float* ray_gain) {
  if (!(max_share > 0.0 && max_share <= 1.0) || n < 1 || !(lambda_e >= 0.0)) {
    throw std::invalid_argument("TestHiddenUnits: bad share, ray count or lambda_e");
  }
  const int h = model.head().config().hidden;
  HiddenDecision d;
  d.keep1.assign(h, 1);
  d.keep2.assign(h, 1);
  if (h == 0) return d;  // spherical harmonics: no hidden units
  TensorfModel work = model;
  d.mse = RenderMse(work, n, origins, dirs, rgb, ray_gain);
  std::vector<float> saved;
  const int layers = model.head().config().hidden_layers;
  for (int layer = 1; layer <= layers; ++layer) {
    std::vector<double>& dmse = layer == 1 ? d.dmse1 : d.dmse2;
    dmse.resize(h);
    for (int u = 0; u < h; ++u) {
      SetHiddenUnit(&work.head(), layer, u, &saved, false);
      dmse[u] = RenderMse(work, n, origins, dirs, rgb, ray_gain) - d.mse;
      SetHiddenUnit(&work.head(), layer, u, &saved, true);
    }
  }
  std::vector<int> order1(h), order2(h);
  std::iota(order1.begin(), order1.end(), 0);
  std::stable_sort(order1.begin(), order1.end(),
                   [&](int a, int b) { return d.dmse1[a] < d.dmse1[b]; });
  if (layers == 1) {  // W3 reads the first layer: a unit is one "pair", counted once
    d.dmse2.assign(h, 0.0);
    order2 = order1;
  } else {
    std::iota(order2.begin(), order2.end(), 0);
    std::stable_sort(order2.begin(), order2.end(),
                     [&](int a, int b) { return d.dmse2[a] < d.dmse2[b]; });
  }
  // The bits the first k pairs save, from the coded head without them.
  const double full_bits = HeadBits(model.head(), mlp_levels);
  auto keep_for = [&](int k, std::vector<uint8_t>* k1, std::vector<uint8_t>* k2) {
    k1->assign(h, 1);
    k2->assign(h, 1);
    for (int p = 0; p < k; ++p) {
      (*k1)[order1[p]] = 0;
      (*k2)[order2[p]] = 0;
    }
  };
  auto bits_saved = [&](int k) {
    std::vector<uint8_t> k1, k2;
    keep_for(k, &k1, &k2);
    AppearanceHead smaller = model.head();
    smaller.KeepHidden(k1, k2);
    return full_bits - HeadBits(smaller, mlp_levels);
  };
  const int limit = std::min(h - 1, static_cast<int>(std::floor(max_share * h)));
  // The most pairs whose summed single-unit losses are below their bits' worth...
  int marked = 0;
  double summed = 0.0;
  for (int k = 1; k <= limit; ++k) {
    summed += d.dmse1[order1[k - 1]] + d.dmse2[order2[k - 1]];
    if (summed < lambda_e * bits_saved(k)) marked = k;
  }
  // ... then fewer until they pay jointly.
  auto joint_pays = [&](int k) {
    TensorfModel trial = model;
    for (int p = 0; p < k; ++p) {
      SetHiddenUnit(&trial.head(), 1, order1[p], &saved, false);
      if (layers == 2) SetHiddenUnit(&trial.head(), 2, order2[p], &saved, false);
    }
    return RenderMse(trial, n, origins, dirs, rgb, ray_gain) - d.mse < lambda_e * bits_saved(k);
  };
  int k = marked;
  while (k > 0 && !joint_pays(k)) k /= 2;
  keep_for(k, &d.keep1, &d.keep2);
  d.dropped = k;
  d.bits = k > 0 ? bits_saved(k) : 0.0;
  return d;
}

void PruneHidden(const HiddenDecision& decision, TensorfModel* model, Optimizers* opt) {
  if (decision.dropped == 0) return;
  if (decision.keep1.size() != size_t(model->head().config().hidden)) {
    throw std::invalid_argument("PruneHidden: the decision is for another head");
  }
  if (opt->head.size() == model->head().params().size()) {
    opt->head.Keep(model->head().KeptHiddenIndices(decision.keep1, decision.keep2));
  }
  model->KeepHidden(decision.keep1, decision.keep2);
}

PruneDecision TestComponents(const TensorfModel& model, const RateState& rate, double lambda_e,
                             int n, const float* origins, const float* dirs, const float* rgb,
                             double max_share, const float* ray_gain) {
  if (!rate.active || rate.steps.size() != 2 * encoder::kTensorsPerGrid) {
    throw std::invalid_argument("TestComponents: the rate objective is not active");
  }
  if (!(max_share > 0.0 && max_share <= 1.0) || n < 1 || !(lambda_e >= 0.0)) {
    throw std::invalid_argument("TestComponents: bad share, ray count or lambda_e");
  }
  PruneDecision d;
  TensorfModel work = model;  // its line channels are zeroed one at a time
  d.mse = RenderMse(work, n, origins, dirs, rgb, ray_gain);
  for (int g = 0; g < 2; ++g) {
    const VmGrid& grid = GridOf(model, g);
    for (int m = 0; m < 3; ++m) {
      const int rank = grid.ranks()[m];
      d.keep[g][m].assign(rank, 1);
      const double with_all = ModeBits(grid, g, m, rate);
      std::vector<ComponentTest> tests(rank);
      for (int r = 0; r < rank; ++r) {
        ComponentTest& t = tests[r];
        t.grid = g;
        t.mode = m;
        t.component = r;
        // Zeroing the line channel zeroes the component's products plane x line everywhere.
        VmGrid& wg = GridOf(work, g);
        float* line = wg.line(m);
        const size_t cells = wg.line_size(m) / size_t(rank);
        std::vector<float> kept(cells);
        for (size_t i = 0; i < cells; ++i) {
          kept[i] = line[i * rank + r];
          line[i * rank + r] = 0.f;
        }
        t.dmse = RenderMse(work, n, origins, dirs, rgb, ray_gain) - d.mse;
        for (size_t i = 0; i < cells; ++i) line[i * rank + r] = kept[i];
        if (rank > 1) {
          std::array<std::vector<uint8_t>, 3> keep;
          for (int k = 0; k < 3; ++k) keep[k].assign(grid.ranks()[k], 1);
          keep[m][r] = 0;
          VmGrid reduced = grid;
          reduced.KeepComponents(keep);
          t.bits = with_all - ModeBits(reduced, g, m, rate);
        }
      }
      // The least worth first: MSE per bit saved, against lambda_e.
      std::vector<int> order(rank);
      std::iota(order.begin(), order.end(), 0);
      auto worth = [&](int r) {
        return tests[r].bits > 0.0 ? tests[r].dmse / tests[r].bits : INFINITY;
      };
      std::stable_sort(order.begin(), order.end(),
                       [&](int a, int b) { return worth(a) < worth(b); });
      // Each test zeroes one component, so it misses how the MSE of several grows together
      // (quadratically in the summed change of the features): the drops are then tested jointly,
      // keeping the longest prefix of the order whose joint MSE rise is below lambda_e times the
      // bits it saves (found by halving).
      const int limit = std::min(rank - 1, static_cast<int>(std::floor(max_share * rank)));
      int marked = 0;
      while (marked < limit && tests[order[marked]].bits > 0.0 &&
             tests[order[marked]].dmse < lambda_e * tests[order[marked]].bits) {
        ++marked;
      }
      VmGrid& wg = GridOf(work, g);
      const size_t cells = wg.line_size(m) / size_t(rank);
      const std::vector<float> line_kept(wg.line(m), wg.line(m) + wg.line_size(m));
      auto joint_pays = [&](int k) {
        double bits = 0.0;
        float* line = wg.line(m);
        for (int j = 0; j < k; ++j) {
          bits += tests[order[j]].bits;
          for (size_t i = 0; i < cells; ++i) line[i * rank + order[j]] = 0.f;
        }
        const double dmse = RenderMse(work, n, origins, dirs, rgb, ray_gain) - d.mse;
        std::copy(line_kept.begin(), line_kept.end(), line);
        return dmse < lambda_e * bits;
      };
      int dropped = marked;
      while (dropped > 1 && !joint_pays(dropped)) dropped /= 2;
      for (int j = 0; j < dropped; ++j) {
        tests[order[j]].drop = true;
        d.keep[g][m][order[j]] = 0;
      }
      d.dropped += dropped;
      d.tests.insert(d.tests.end(), tests.begin(), tests.end());
    }
  }
  return d;
}

void PruneComponents(const PruneDecision& decision, TensorfModel* model, Optimizers* opt) {
  for (int g = 0; g < 2; ++g) {
    const auto& keep = decision.keep[g];
    bool any = false;
    for (int m = 0; m < 3; ++m) {
      if (keep[m].size() != static_cast<size_t>(GridOf(*model, g).ranks()[m])) {
        throw std::invalid_argument("PruneComponents: the decision is for another model");
      }
      any = any || std::find(keep[m].begin(), keep[m].end(), 0) != keep[m].end();
    }
    if (!any) continue;
    VmGrid& grid = GridOf(*model, g);
    Adam& adam = g == 0 ? opt->density : opt->appearance;
    if (adam.size() == grid.params().size()) adam.Keep(grid.KeptIndices(keep));
    if (g == 1) {
      std::vector<uint8_t> products;
      for (int m = 0; m < 3; ++m) products.insert(products.end(), keep[m].begin(), keep[m].end());
      if (opt->head.size() == model->head().params().size()) {
        opt->head.Keep(model->head().KeptIndices(products));
      }
    }
    model->KeepComponents(g, keep);
  }
}

}  // namespace trainer
}  // namespace ecrf
