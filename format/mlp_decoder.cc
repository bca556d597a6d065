#include "format/byte_io.h"
#include "format/half_float.h"
#include "format/mlp_coder.h"

namespace ecrf {
Status DecodeQuantizedMlp(const MlpLayout& layout, const uint8_t* data, size_t size,
                          float* params_out) {
  MlpMatrixSpan matrices[4], biases[3];
  MlpMatrices(layout, matrices, biases);
  ByteReader r(data, size);
  // Steps are read into the first value of each row and replaced as the row decodes.
  size_t row_index = 0;
  for (const MlpMatrixSpan& m : matrices) {
    for (int row = 0; row < m.rows; ++row, ++row_index) {
      uint16_t half = 0;
      ECRF_RETURN_IF_ERROR(r.ReadU16(&half, "MLPW step"));
      ECRF_CHECK_OR_RETURN(HalfIsFinite(half), kErrCorrupt, "MLPW: step of row %zu is not finite",
                           row_index);
      params_out[m.offset + static_cast<size_t>(row) * m.cols] = HalfToFloat(half);
    }
  }
  for (const MlpMatrixSpan& b : biases) {
    for (int c = 0; c < b.cols; ++c) {
      uint16_t half = 0;
      ECRF_RETURN_IF_ERROR(r.ReadU16(&half, "MLPW bias"));
      ECRF_CHECK_OR_RETURN(HalfIsFinite(half), kErrCorrupt, "MLPW: bias value is not finite");
      params_out[b.offset + c] = HalfToFloat(half);
    }
  }
  RangeDecoder dec(r.current(), r.remaining());
  MlpLevelContexts contexts;
  for (int mi = 0; mi < 4; ++mi) {
    const MlpMatrixSpan& m = matrices[mi];
    for (int row = 0; row < m.rows; ++row) {
      float* values = params_out + m.offset + static_cast<size_t>(row) * m.cols;
      const float step = values[0];
      int prev_class = 0;
      for (int c = 0; c < m.cols; ++c) {
        uint16_t* cdf =
            contexts.level_class[MlpContextGroup(layout, mi, c)][MlpClassBucket(prev_class)];
        int cls = dec.DecodeSymbol(cdf, kMlpClassEscape + 1);
        if (cls == kMlpClassEscape) {
          const uint32_t extra = dec.DecodeGolomb(0);
          ECRF_CHECK_OR_RETURN(extra <= static_cast<uint32_t>(kMlpMaxClass - kMlpClassEscape),
                               kErrCorrupt, "MLPW: level class %u above %d",
                               extra + kMlpClassEscape, kMlpMaxClass);
          cls += static_cast<int>(extra);
        }
        uint32_t mag = 0;
        if (cls >= 1) mag = (1u << (cls - 1)) | (cls >= 2 ? dec.DecodeBypass(cls - 1) : 0u);
        const int32_t level = cls != 0 && dec.DecodeBypassBit() ? -static_cast<int32_t>(mag)
                                                                : static_cast<int32_t>(mag);
        prev_class = cls;
        values[c] = static_cast<float>(level) * step;  // |level| < 2^24: exact; one rounding
      }
      if (dec.HasError()) return dec.status();
    }
  }
  return dec.Finish();
}

}  // namespace ecrf
