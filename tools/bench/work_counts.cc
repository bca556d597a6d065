#include "tools/bench/work_counts.h"

namespace ecrf {
namespace tools {

MlpFlops HeadFlops(const trainer::AppearanceHeadConfig& cfg, const trainer::AppearanceHead& head,
                   long n) {
  const double P = cfg.num_products, F = cfg.feature_dim, H = cfg.hidden;
  const double in = head.mlp_input_dim();
  // Hidden-to-hidden layers: one with TensoRF's two hidden layers, none with one (or no MLP).
  const double hh = cfg.hidden > 0 && cfg.hidden_layers > 1 ? H * H : 0.0;
  MlpFlops flops;
  flops.forward = 2.0 * n * (P * F + in * H + hh + H * 3.0);
  // Backward computes dL/dx only for the columns that reach the features (not the view PE), and
  // every weight's gradient.
  const double in_grad = in - 2.0 * 3 * cfg.viewdir_pe_freqs;
  flops.backward = 2.0 * n * (2.0 * H * 3 + 2.0 * hh + (in + in_grad) * H + 2.0 * F * P);
  return flops;
}

ScatterWork ScatterCounts(long density_samples, int density_rank_sum, long appearance_samples,
                          int appearance_rank_sum) {
  constexpr double kCornersPerMode = 4 + 2;  // bilinear plane, linear line
  const double entries = kCornersPerMode * (double(density_samples) * density_rank_sum +
                                            double(appearance_samples) * appearance_rank_sum);
  ScatterWork w;
  w.flops = 2.0 * entries;
  w.bytes = 8.0 * entries;
  return w;
}

}  // namespace tools
}  // namespace ecrf
