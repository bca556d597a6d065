#include "format/mlp_coder.h"

namespace ecrf {

void MlpMatrices(const MlpLayout& l, MlpMatrixSpan matrices[4], MlpMatrixSpan biases[3]) {
  const size_t F = static_cast<size_t>(l.feature_dim), P = static_cast<size_t>(l.num_products);
  const size_t H = static_cast<size_t>(l.hidden), In = static_cast<size_t>(l.input_dim);
  const int h2 = l.hidden_layers == 2 ? l.hidden : 0;  // W2's rows and columns
  const size_t H2 = static_cast<size_t>(h2);
  size_t at = 0;
  matrices[0] = {at, l.feature_dim, l.num_products};
  at += F * P;
  matrices[1] = {at, l.hidden, l.input_dim};
  at += H * In;
  biases[0] = {at, 1, l.hidden};
  at += H;
  matrices[2] = {at, h2, h2};
  at += H2 * H2;
  biases[1] = {at, 1, h2};
  at += H2;
  matrices[3] = {at, 3, l.hidden};
  at += 3 * H;
  biases[2] = {at, 1, 3};
}

MlpLayout MakeMlpLayout(int feature_dim, int num_products, int hidden, int feature_pe_freqs,
                        int viewdir_pe_freqs, int hidden_layers) {
  MlpLayout l;
  l.hidden_layers = hidden_layers;
  l.feature_dim = feature_dim;
  l.num_products = num_products;
  l.hidden = hidden;
  l.feature_pe_width = 2 * feature_dim * feature_pe_freqs;
  l.input_dim = feature_dim + 3 + l.feature_pe_width + 2 * 3 * viewdir_pe_freqs;
  return l;
}

size_t MlpParamCount(const MlpLayout& l) {
  const size_t F = static_cast<size_t>(l.feature_dim), P = static_cast<size_t>(l.num_products);
  const size_t H = static_cast<size_t>(l.hidden), In = static_cast<size_t>(l.input_dim);
  const size_t H2 = l.hidden_layers == 2 ? H : 0;
  return F * P + H * In + H + H2 * H2 + H2 + 3 * H + 3;
}

int MlpContextGroup(const MlpLayout& l, int matrix, int col) {
  if (matrix == 0) return 0;
  if (matrix >= 2) return matrix + 3;
  if (col < l.feature_dim) return 1;
  if (col < l.feature_dim + 3) return 2;
  return col < l.feature_dim + 3 + l.feature_pe_width ? 3 : 4;
}

MlpLevelContexts::MlpLevelContexts() {
  for (auto& group : level_class) {
    for (auto& cdf : group) InitUniformCdf(cdf, kMlpClassEscape + 1);
  }
}

}  // namespace ecrf
