#include "tools/encode_report.h"

#include <algorithm>

#include "trainer/train/rate_state.h"

namespace ecrf {
namespace tools {

void PrintEncodeReport(FILE* out, const encoder::EncodeReport& r) {
  std::fprintf(out, "%-20s %10s %9s %12s %8s %10s\n", "chunk", "bytes", "bits/coef", "zero blocks",
               "rank", "step");
  std::fprintf(out, "%-20s %10zu\n", "HEAD", r.head_bytes);
  if (r.occupancy_bytes) std::fprintf(out, "%-20s %10zu\n", "OCCU", r.occupancy_bytes);
  for (int t = 0; t < 12; ++t) {
    const int g = t / 6, m = (t % 6) % 3;
    char rank[32];
    std::snprintf(rank, sizeof(rank), "%d/%d", r.ranks_out[g][m], r.ranks_in[g][m]);
    if (r.tensor_bytes[t] == 0) {
      std::fprintf(out, "%-20s %10s %9s %12s %8s\n", encoder::RateTensorName(t), "dropped", "", "",
                   rank);
      continue;
    }
    char zero[32];
    std::snprintf(zero, sizeof(zero), "%zu/%zu", r.tensor_zero_blocks[t], r.tensor_blocks[t]);
    std::fprintf(out, "%-20s %10zu %9.4f %12s %8s %10.3g\n", encoder::RateTensorName(t),
                 r.tensor_bytes[t],
                 8.0 * r.tensor_bytes[t] / std::max<size_t>(1, r.tensor_coeffs[t]), zero, rank,
                 double(r.steps[t]));
  }
  std::fprintf(out, "%-20s %10zu\n", "MLPW", r.mlp_bytes);
  if (r.metadata_bytes) std::fprintf(out, "%-20s %10zu\n", "meta", r.metadata_bytes);
  std::fprintf(out, "%-20s %10zu\n", "container", r.container_bytes);
  std::fprintf(out, "%-20s %10zu  (coefficients %zu)\n", "total", r.total_bytes,
               r.coefficient_bytes());
  if (r.clipped_coefficients) {
    std::fprintf(out, "warning: %zu coefficients exceeded the coefficient range and were clamped\n",
                 r.clipped_coefficients);
  }
}

nlohmann::json EncodeReportJson(const encoder::EncodeReport& r) {
  nlohmann::json j;
  j["total_bytes"] = r.total_bytes;
  j["coefficient_bytes"] = r.coefficient_bytes();
  j["head_bytes"] = r.head_bytes;
  j["occupancy_bytes"] = r.occupancy_bytes;
  j["mlp_bytes"] = r.mlp_bytes;
  j["metadata_bytes"] = r.metadata_bytes;
  j["container_bytes"] = r.container_bytes;
  j["clipped_coefficients"] = r.clipped_coefficients;
  nlohmann::json tensors = nlohmann::json::object();
  for (int t = 0; t < 12; ++t) {
    tensors[encoder::RateTensorName(t)] = {{"bytes", r.tensor_bytes[t]},
                                           {"coefficients", r.tensor_coeffs[t]},
                                           {"blocks", r.tensor_blocks[t]},
                                           {"zero_blocks", r.tensor_zero_blocks[t]},
                                           {"step", r.steps[t]},
                                           {"rank_coded", r.ranks_out[t / 6][(t % 6) % 3]},
                                           {"rank_trained", r.ranks_in[t / 6][(t % 6) % 3]}};
  }
  j["tensors"] = tensors;
  return j;
}

}  // namespace tools
}  // namespace ecrf
