#include "trainer/rate/rate_objective.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

namespace ecrf {
namespace trainer {
namespace {

uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// In-block positions grouped by band: positions perm[begin[b] .. begin[b+1]) have band b.
struct BandMap {
  std::vector<int> perm;
  int begin[kNumFrequencyBands + 1];
};

BandMap MakeBandMap(const encoder::GridBlockLayout& L, bool line) {
  BandMap bm;
  std::vector<int> band(L.block_volume());
  int count[kNumFrequencyBands] = {0};
  for (int k0 = 0, p = 0; k0 < L.block[0]; ++k0) {
    for (int k1 = 0; k1 < L.block[1]; ++k1) {
      for (int k2 = 0; k2 < L.block[2]; ++k2, ++p) {
        band[p] = FrequencyBand(line, k0, k1, k2);
        ++count[band[p]];
      }
    }
  }
  bm.begin[0] = 0;
  for (int b = 0; b < kNumFrequencyBands; ++b) bm.begin[b + 1] = bm.begin[b] + count[b];
  bm.perm.resize(band.size());
  int fill[kNumFrequencyBands];
  std::copy(bm.begin, bm.begin + kNumFrequencyBands, fill);
  for (int p = 0; p < static_cast<int>(band.size()); ++p) bm.perm[fill[band[p]]++] = p;
  return bm;
}

enum class Mode { kNoisyTrain, kRoundedEval };

struct TensorResult {
  double bits = 0.0;  // unscaled sum over the processed blocks
  double reg = 0.0;
};

// Processes the listed blocks of one tensor. grad == nullptr: no gradients.
TensorResult ProcessTensor(const float* tensor, float* grad, const encoder::GridBlockLayout& L,
                           const std::vector<int>& ids, float step, int tensor_index,
                           FactorizedEntropyModel* model, Mode mode, float scale, float lambda_e,
                           float lambda_r, uint64_t seed) {
  const int k = static_cast<int>(ids.size());
  const int V = L.block_volume();
  const size_t total = static_cast<size_t>(k) * V;
  const BandMap bm = MakeBandMap(L, tensor_index % encoder::kTensorsPerGrid >= 3);
  std::vector<float> c(total), x(total);
  encoder::ForwardBlockList(tensor, L, ids.data(), k, c.data());
  const float inv_step = 1.f / step;
  const uint64_t stream = SplitMix64(seed * 0x2545F4914F6CDD1Dull + tensor_index);
  double reg = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : reg) if (total > 65536)
  for (int j = 0; j < k; ++j) {
    const float* cj = c.data() + static_cast<size_t>(j) * V;
    for (int b = 0; b < kNumFrequencyBands; ++b) {
      const int cnt = bm.begin[b + 1] - bm.begin[b];
      float* xb = x.data() + static_cast<size_t>(k) * bm.begin[b] + static_cast<size_t>(j) * cnt;
      const int* pb = bm.perm.data() + bm.begin[b];
      for (int q = 0; q < cnt; ++q) {
        const float v = cj[pb[q]] * inv_step;
        if (mode == Mode::kRoundedEval) {
          xb[q] = std::round(v);
        } else {
          const uint64_t h = SplitMix64(stream + static_cast<uint64_t>(ids[j]) * V + pb[q]);
          xb[q] = v + (static_cast<float>(h >> 40) * (1.f / 16777216.f) - 0.5f);
        }
      }
    }
    double r = 0.0;
    for (int p = 0; p < V; ++p) r += static_cast<double>(cj[p]) * cj[p];
    reg += r;
  }
  std::vector<EntropySegment> segs;
  for (int b = 0; b < kNumFrequencyBands; ++b) {
    const size_t lo = static_cast<size_t>(k) * bm.begin[b];
    const size_t hi = static_cast<size_t>(k) * bm.begin[b + 1];
    if (hi > lo) segs.push_back({RateModelIndex(tensor_index, b), lo, hi});
  }
  TensorResult res;
  res.reg = reg;
  if (!grad) {
    res.bits = model->Bits(x.data(), segs.data(), static_cast<int>(segs.size()), nullptr, nullptr,
                           0.f, false);
    return res;
  }
  // dx = scale * d bits / d x; the model's parameter gradients get the same scale.
  std::vector<float>& dx = x;  // Bits reads x chunk by chunk before writing dx for it
  std::vector<float> xin(x);
  res.bits = model->Bits(xin.data(), segs.data(), static_cast<int>(segs.size()), nullptr, dx.data(),
                         scale, true);
  xin.clear();
  xin.shrink_to_fit();
  // d loss / d coeff = lambda_e * dx / step + 2 lambda_r scale c, written over c.
  const float ge = lambda_e * inv_step;
  const float gr = 2.f * lambda_r * scale;
#pragma omp parallel for schedule(static) if (total > 65536)
  for (int j = 0; j < k; ++j) {
    float* cj = c.data() + static_cast<size_t>(j) * V;
    for (int p = 0; p < V; ++p) cj[p] *= gr;
    for (int b = 0; b < kNumFrequencyBands; ++b) {
      const int cnt = bm.begin[b + 1] - bm.begin[b];
      const float* db =
          dx.data() + static_cast<size_t>(k) * bm.begin[b] + static_cast<size_t>(j) * cnt;
      const int* pb = bm.perm.data() + bm.begin[b];
      for (int q = 0; q < cnt; ++q) cj[pb[q]] += ge * db[q];
    }
  }
  encoder::BackwardBlockList(c.data(), L, ids.data(), k, grad);
  return res;
}

void CheckArgs(size_t num_grids, const std::vector<float>& steps,
               const FactorizedEntropyModel& model) {
  if (steps.size() != num_grids * encoder::kTensorsPerGrid) {
    throw std::invalid_argument("rate_objective: need one step per tensor (6 per grid)");
  }
  for (float s : steps) {
    if (!(s > 0.f)) throw std::invalid_argument("rate_objective: steps must be > 0");
  }
  if (model.num_models() < NumRateModels(static_cast<int>(num_grids))) {
    throw std::invalid_argument("rate_objective: entropy model has too few models");
  }
}

}  // namespace

int FrequencyOctave(int s) {
  int l = 0;
  while (l < 5 && (1 << l) <= s) ++l;  // 1 + floor(log2(s)) for s >= 1
  return l;
}

int FrequencyBand(bool line, int k0, int k1, int k2) {
  const int kc = line ? k1 : k0;
  const int ks = line ? k2 : k1 + k2;
  return 6 * FrequencyOctave(kc) + FrequencyOctave(ks);
}

RateEstimate AddRateGradients(const std::vector<VmGrid*>& grids, const std::vector<float>& steps,
                              const encoder::RateConfig& config, FactorizedEntropyModel* model,
                              float lambda_e, float lambda_r, float fraction, uint64_t seed) {
  CheckArgs(grids.size(), steps, *model);
  if (!(fraction > 0.f)) throw std::invalid_argument("AddRateGradients: fraction must be > 0");
  RateEstimate est;
  for (size_t g = 0; g < grids.size(); ++g) {
    VmGrid& grid = *grids[g];
    for (int t = 0; t < encoder::kTensorsPerGrid; ++t) {
      const int ti = static_cast<int>(g) * encoder::kTensorsPerGrid + t;
      const encoder::GridBlockLayout L = RateTensorLayout(grid, t, config);
      const int n = L.num_blocks();
      int k =
          fraction >= 1.f ? n : static_cast<int>(std::lround(fraction * static_cast<double>(n)));
      k = std::min(n, std::max(1, k));
      std::vector<int> ids(n);
      std::iota(ids.begin(), ids.end(), 0);
      if (k < n) {
        std::mt19937_64 rng(SplitMix64(seed ^ (0x9E3779B97F4A7C15ull * (ti + 1))));
        for (int i = 0; i < k; ++i) {  // partial Fisher-Yates
          std::uniform_int_distribution<int> pick(i, n - 1);
          std::swap(ids[i], ids[pick(rng)]);
        }
        ids.resize(k);
        std::sort(ids.begin(), ids.end());
      }
      const float scale = static_cast<float>(static_cast<double>(n) / k);
      const TensorResult r =
          ProcessTensor(RateTensorData(grid, t), RateTensorGrad(grid, t), L, ids, steps[ti], ti,
                        model, Mode::kNoisyTrain, scale, lambda_e, lambda_r, seed);
      est.bits += static_cast<double>(scale) * r.bits;
      est.regularizer += static_cast<double>(scale) * r.reg;
    }
  }
  return est;
}

double EvaluateTensorBits(const VmGrid& grid, int t, float step, int tensor_index,
                          const encoder::RateConfig& config, const FactorizedEntropyModel& model) {
  if (t < 0 || t >= encoder::kTensorsPerGrid || !(step > 0.f) || tensor_index < 0 ||
      RateModelIndex(tensor_index, kNumFrequencyBands - 1) >= model.num_models()) {
    throw std::invalid_argument("EvaluateTensorBits: bad tensor, step or model count");
  }
  // Bits() without gradients does not modify the model.
  FactorizedEntropyModel* m = const_cast<FactorizedEntropyModel*>(&model);
  const encoder::GridBlockLayout L = RateTensorLayout(grid, t, config);
  std::vector<int> ids(L.num_blocks());
  std::iota(ids.begin(), ids.end(), 0);
  return ProcessTensor(RateTensorData(grid, t), nullptr, L, ids, step, tensor_index, m,
                       Mode::kRoundedEval, 1.f, 0.f, 0.f, 0)
      .bits;
}

RateReport EvaluateRate(const std::vector<const VmGrid*>& grids, const std::vector<float>& steps,
                        const encoder::RateConfig& config, const FactorizedEntropyModel& model) {
  CheckArgs(grids.size(), steps, model);
  RateReport rep;
  for (size_t g = 0; g < grids.size(); ++g) {
    for (int t = 0; t < encoder::kTensorsPerGrid; ++t) {
      const int ti = static_cast<int>(g) * encoder::kTensorsPerGrid + t;
      const double bits = EvaluateTensorBits(*grids[g], t, steps[ti], ti, config, model);
      rep.bits.push_back(bits);
      rep.coeffs.push_back(RateTensorLayout(*grids[g], t, config).num_coeffs());
      rep.total_bits += bits;
    }
  }
  return rep;
}

}  // namespace trainer
}  // namespace ecrf
