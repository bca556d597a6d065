// libFuzzer target: quantized MLP weights (MLPW precision 2) from arbitrary bytes must end in an
// error status or finite weights, never a crash, an out-of-bounds access or a hang.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "format/mlp_coder.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  // The first two bytes pick a small layout; the rest is the payload after the 4-byte header.
  const ecrf::MlpLayout l =
      ecrf::MakeMlpLayout(1 + data[0] % 8, 1 + (data[0] >> 3) % 12, 1 + data[1] % 16,
                          (data[1] >> 4) % 3, (data[1] >> 6) % 3);
  std::vector<float> params(ecrf::MlpParamCount(l));
  if (!ecrf::DecodeQuantizedMlp(l, data + 2, size - 2, params.data()).ok()) return 0;
  for (float v : params) {
    if (!std::isfinite(v)) std::abort();  // 6.6.1: every decoded weight is finite
  }
  return 0;
}
