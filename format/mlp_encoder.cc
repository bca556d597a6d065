#include <cmath>
#include <cstdlib>

#include "format/byte_io.h"
#include "format/half_float.h"
#include "format/mlp_coder.h"

namespace ecrf {

std::vector<uint8_t> EncodeQuantizedMlp(const MlpLayout& layout, const float* params, int max_level,
                                        std::vector<float>* reconstructed) {
  MlpMatrixSpan matrices[4], biases[3];
  MlpMatrices(layout, matrices, biases);
  if (reconstructed) reconstructed->assign(params, params + MlpParamCount(layout));
  ByteWriter head;
  RangeEncoder enc;
  MlpLevelContexts contexts;
  // Steps first (all rows of all matrices), then biases, then the level stream: the decoder
  // knows every size from the header before it reads a level.
  std::vector<float> steps;
  for (const MlpMatrixSpan& m : matrices) {
    for (int r = 0; r < m.rows; ++r) {
      float peak = 0.f;
      for (int c = 0; c < m.cols; ++c)
        peak = std::fmax(peak, std::fabs(params[m.offset + size_t(r) * m.cols + c]));
      uint16_t half = FloatToHalf(peak / static_cast<float>(max_level));
      if (!HalfIsFinite(half)) half = 0x7BFF;  // beyond binary16: the largest finite step
      head.U16(half);
      steps.push_back(HalfToFloat(half));
    }
  }
  for (const MlpMatrixSpan& b : biases) {
    for (int c = 0; c < b.cols; ++c) {
      const uint16_t half = FloatToHalf(params[b.offset + c]);
      head.U16(half);
      if (reconstructed) (*reconstructed)[b.offset + c] = HalfToFloat(half);
    }
  }
  size_t row_index = 0;
  for (int mi = 0; mi < 4; ++mi) {
    const MlpMatrixSpan& m = matrices[mi];
    for (int r = 0; r < m.rows; ++r, ++row_index) {
      const float step = steps[row_index];
      int prev_class = 0;
      for (int c = 0; c < m.cols; ++c) {
        const size_t i = m.offset + size_t(r) * m.cols + c;
        // A zero step (an all-zero row, or one too small for binary16) codes zeros.
        const double q = step > 0.f ? std::nearbyint(double(params[i]) / step) : 0.0;
        const int32_t level =
            static_cast<int32_t>(std::fmax(-kMlpMaxLevel, std::fmin(kMlpMaxLevel, q)));
        const uint32_t mag = static_cast<uint32_t>(std::abs(level));
        const int cls = MlpLevelClass(mag);
        uint16_t* cdf =
            contexts.level_class[MlpContextGroup(layout, mi, c)][MlpClassBucket(prev_class)];
        enc.EncodeSymbol(cls < kMlpClassEscape ? cls : kMlpClassEscape, cdf, kMlpClassEscape + 1);
        if (cls >= kMlpClassEscape)
          enc.EncodeGolomb(static_cast<uint32_t>(cls - kMlpClassEscape), 0);
        if (cls >= 2) enc.EncodeBypass(mag - (1u << (cls - 1)), cls - 1);
        if (cls != 0) enc.EncodeBypass(level < 0 ? 1u : 0u, 1);
        prev_class = cls;
        if (reconstructed) (*reconstructed)[i] = static_cast<float>(level) * step;
      }
    }
  }
  std::vector<uint8_t> out = head.bytes();
  const std::vector<uint8_t> levels = enc.Finish();
  out.insert(out.end(), levels.begin(), levels.end());
  return out;
}

}  // namespace ecrf
