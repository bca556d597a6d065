#include "trainer/rate/quant_aware.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <utility>

#include "encoder/coef_quantizer.h"
#include "encoder/coef_rdoq.h"
#include "encoder/grid_dct.h"

namespace ecrf {
namespace trainer {

namespace {

// The RDOQ version: the six tensors' coefficients first (each transform runs in parallel), then
// their levels side by side (each tensor's coder state is sequential), then the inverses.
void ReconstructRdoqGrid(const VmGrid& grid, const float* steps, const encoder::RateConfig& config,
                         std::vector<float>* out, float rounding_offset, float rdoq_lambda) {
  encoder::GridBlockLayout layouts[encoder::kTensorsPerGrid];
  std::vector<float> coeffs[encoder::kTensorsPerGrid];
  for (int t = 0; t < encoder::kTensorsPerGrid; ++t) {
    layouts[t] = RateTensorLayout(grid, t, config);
    coeffs[t].resize(layouts[t].num_coeffs());
    encoder::ForwardBlocks(RateTensorData(grid, t), layouts[t], coeffs[t].data());
  }
  encoder::RdoqOptions rdoq;
  rdoq.lambda = rdoq_lambda;
  rdoq.rounding_offset = rounding_offset;
  rdoq.max_abs = std::numeric_limits<int32_t>::max();  // as the rounding path: unclipped
#pragma omp parallel for schedule(dynamic, 1)
  for (int t = 0; t < encoder::kTensorsPerGrid; ++t) {
    std::vector<int32_t> levels(coeffs[t].size());
    encoder::RdoqLevels(coeffs[t].data(), layouts[t], steps[t], rdoq, levels.data());
    for (size_t i = 0; i < levels.size(); ++i) coeffs[t][i] = float(double(levels[i]) * steps[t]);
  }
  for (int t = 0; t < encoder::kTensorsPerGrid; ++t) {
    const size_t offset = static_cast<size_t>(RateTensorData(grid, t) - grid.params().data());
    encoder::InverseBlocks(coeffs[t].data(), layouts[t], out->data() + offset);
  }
}

}  // namespace

void ReconstructQuantizedGrid(const VmGrid& grid, const float* steps,
                              const encoder::RateConfig& config, std::vector<float>* out,
                              float rounding_offset, float rdoq_lambda) {
  // The six tensors tile params() and QuantizeBlocks writes every element of each: no copy.
  out->resize(grid.params().size());
  if (rdoq_lambda > 0.f) {
    ReconstructRdoqGrid(grid, steps, config, out, rounding_offset, rdoq_lambda);
    return;
  }
  for (int t = 0; t < encoder::kTensorsPerGrid; ++t) {
    const size_t offset = static_cast<size_t>(RateTensorData(grid, t) - grid.params().data());
    encoder::QuantizeBlocks(RateTensorData(grid, t), RateTensorLayout(grid, t, config), steps[t],
                            rounding_offset, out->data() + offset);
  }
}

MlpLayout HeadMlpLayout(const AppearanceHeadConfig& h) {
  return MakeMlpLayout(h.feature_dim, h.num_products, h.hidden, h.feature_pe_freqs,
                       h.viewdir_pe_freqs, h.hidden_layers);
}

void ReconstructQuantizedHead(const TensorfModel& model, int max_level, std::vector<float>* out) {
  const MlpLayout layout = HeadMlpLayout(model.config().head);
  if (MlpParamCount(layout) != model.head().params().size()) {
    throw std::logic_error("ReconstructQuantizedHead: the head's layout is not the stream's");
  }
  // The coder's own quantizer, so training sees exactly what the decoder will (the coded bytes
  // are a by-product, a millisecond for a 40k-parameter head).
  EncodeQuantizedMlp(layout, model.head().params().data(), max_level, out);
}

std::vector<float>& QuantAwareModel::Params(TensorfModel* model, int k) {
  return k == 0   ? model->density().params()
         : k == 1 ? model->appearance().params()
                  : model->head().params();
}

void QuantAwareModel::Refresh(const TensorfModel& model, const std::vector<float>& steps,
                              const encoder::RateConfig& config, int mlp_levels,
                              float rounding_offset, float rdoq_lambda) {
  if (applied_) throw std::logic_error("QuantAwareModel::Refresh while applied");
  if (steps.size() != 2 * encoder::kTensorsPerGrid) {
    throw std::invalid_argument("QuantAwareModel: need 12 quantization steps");
  }
  ReconstructQuantizedGrid(model.density(), steps.data(), config, &error_[0], rounding_offset,
                           rdoq_lambda);
  ReconstructQuantizedGrid(model.appearance(), steps.data() + encoder::kTensorsPerGrid, config,
                           &error_[1], rounding_offset, rdoq_lambda);
  error_[2].clear();
  if (mlp_levels > 0) ReconstructQuantizedHead(model, mlp_levels, &error_[2]);
  const std::vector<float>* params[3] = {&model.density().params(), &model.appearance().params(),
                                         &model.head().params()};
  for (int k = 0; k < 3; ++k) {
    if (error_[k].empty()) continue;
    const std::vector<float>& p = *params[k];
    const long n = static_cast<long>(p.size());
#pragma omp parallel for schedule(static) if (n > 65536)
    for (long i = 0; i < n; ++i) error_[k][i] -= p[i];
  }
}

bool QuantAwareModel::fresh_for(const TensorfModel& model) const {
  return error_[0].size() == model.density().params().size() &&
         error_[1].size() == model.appearance().params().size() && !error_[0].empty() &&
         (error_[2].empty() || error_[2].size() == model.head().params().size());
}

void QuantAwareModel::Apply(TensorfModel* model) {
  if (applied_ || !fresh_for(*model))
    throw std::logic_error("QuantAwareModel::Apply: not refreshed");
  for (int k = 0; k < 3; ++k) {
    if (error_[k].empty()) continue;
    std::vector<float>& p = Params(model, k);
    held_[k].resize(p.size());
    std::swap(held_[k], p);  // p is now scratch of the right size; held_ the float values
    const float* src = held_[k].data();
    const float* e = error_[k].data();
    float* dst = p.data();
    const long n = static_cast<long>(p.size());
#pragma omp parallel for schedule(static) if (n > 65536)
    for (long i = 0; i < n; ++i) dst[i] = src[i] + e[i];
  }
  applied_ = true;
}

void QuantAwareModel::Restore(TensorfModel* model) {
  if (!applied_) return;
  for (int k = 0; k < 3; ++k) {
    if (!error_[k].empty()) std::swap(held_[k], Params(model, k));
  }
  applied_ = false;
}

}  // namespace trainer
}  // namespace ecrf
