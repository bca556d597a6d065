#include "format/byte_io.h"
#include "format/half_float.h"
#include "format/mlp_coder.h"

namespace ecrf {

Status ReadMlpChunkHeader(ByteReader* r, int version_minor, int hidden, MlpChunkHeader* out) {
  uint8_t precision = 0, head = 0, layers = 0, reserved = 0;
  ECRF_RETURN_IF_ERROR(r->ReadU8(&precision, "MLPW precision"));
  ECRF_RETURN_IF_ERROR(r->ReadU8(&head, "MLPW head"));
  ECRF_RETURN_IF_ERROR(r->ReadU8(&layers, "MLPW layers"));
  ECRF_RETURN_IF_ERROR(r->ReadU8(&reserved, "MLPW reserved"));
  ECRF_CHECK_OR_RETURN(reserved == 0, kErrCorrupt, "MLPW: the reserved byte must be 0");
  ECRF_CHECK_OR_RETURN(precision <= kMlpPrecisionQuantized, kErrUnsupported,
                       "MLPW: precision %u (0 = float16, 1 = float32, 2 = quantized)", precision);
  ECRF_CHECK_OR_RETURN(
      precision != kMlpPrecisionQuantized || version_minor >= kQuantizedMlpMinVersionMinor,
      kErrCorrupt,
      "MLPW: precision 2 (quantized) needs version_minor >= %d, the stream says %d (SPEC.md 2.1)",
      kQuantizedMlpMinVersionMinor, version_minor);
  ECRF_CHECK_OR_RETURN(head < kNumHeadKinds, kErrUnsupported,
                       "MLPW: head %u is unknown (this decoder knows 0, per-sample MLP, and 1, "
                       "deferred; the stream needs a newer decoder)",
                       head);
  ECRF_CHECK_OR_RETURN(
      version_minor >= kHeadKindMinVersionMinor[head], kErrCorrupt,
      "MLPW: head %u (%s) needs version_minor >= %d, the stream says %d (SPEC.md 2.1; the byte "
      "was reserved, 0, before 1.6)",
      head, HeadKindName(static_cast<HeadKind>(head)), kHeadKindMinVersionMinor[head],
      version_minor);
  ECRF_CHECK_OR_RETURN(layers <= kMlpOneHiddenLayer, kErrUnsupported,
                       "MLPW: layers %u is unknown (this decoder knows 0, two hidden layers, and "
                       "1, one; the stream needs a newer decoder)",
                       layers);
  ECRF_CHECK_OR_RETURN(
      layers == kMlpTwoHiddenLayers || version_minor >= kOneHiddenLayerMinVersionMinor, kErrCorrupt,
      "MLPW: layers 1 (one hidden layer) needs version_minor >= %d, the stream says %d (SPEC.md "
      "2.1; the byte was reserved, 0, before 1.8)",
      kOneHiddenLayerMinVersionMinor, version_minor);
  ECRF_CHECK_OR_RETURN(layers == kMlpTwoHiddenLayers || hidden > 0, kErrCorrupt,
                       "MLPW: layers 1 (one hidden layer) with HEAD hidden 0, which has no MLP");
  out->precision = precision;
  out->head = head;
  out->layers = layers;
  return Status::Ok();
}

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
