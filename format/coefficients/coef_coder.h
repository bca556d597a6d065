// Context-modelled coding of one quantized DCT block (SPEC.md section 4,
// "Coefficient block syntax").
//
// Per block: a coded flag (all-zero blocks cost one well-predicted binary symbol), the
// end-of-block position in scan order, then, in reverse scan order down to DC, each level as a
// base symbol, range symbols and an Exp-Golomb remainder, followed by a bypass sign bit.
// Decoding work is proportional to the end-of-block position, not to the block volume.
#ifndef ECRF_FORMAT_COEFFICIENTS_COEF_CODER_H_
#define ECRF_FORMAT_COEFFICIENTS_COEF_CODER_H_

#include <cstdint>

#include "format/coefficients/coef_contexts.h"
#include "format/coefficients/coef_scan.h"
#include "format/entropy/range_coder.h"
#include "format/status.h"

namespace ecrf {

// Codes the contexts.scan.shape.Volume() coefficients at `coeffs` (raster order). Every value
// must lie in [-(2^31 - 1), 2^31 - 1]; the decoder's max_abs bound is the caller's business.
void EncodeCoefBlock(RangeEncoder& encoder, CoefContexts& contexts, const int32_t* coeffs);

// Decodes one block into coeffs_out (all Volume() values, zeros included). Values whose
// magnitude exceeds max_abs (>= 0) are kErrCorrupt, so for 8-bit tensors with max_abs = 127 the
// value -128 cannot occur. If eob_out is given it receives the end-of-block position: 0 for an
// all-zero block, otherwise 1 + the scan index of the last nonzero coefficient. Errors of the
// range decoder (truncation, bad escapes) are returned too; on error coeffs_out is unspecified.
Status DecodeCoefBlock(RangeDecoder& decoder, CoefContexts& contexts, int32_t max_abs,
                       int32_t* coeffs_out, int* eob_out = nullptr);

}  // namespace ecrf

#endif  // ECRF_FORMAT_COEFFICIENTS_COEF_CODER_H_
