// Rate-distortion optimised quantization (RDOQ) of one tensor's DCT coefficients, the encoder's
// alternative to plain rounding (encoder/coef_quantizer.h), shared with quantization-aware
// training so that training sees the levels the file will carry.
//
// Plain rounding keeps every level whose distortion it lowers, whatever it costs to code. RDOQ,
// as video encoders do it (HEVC's reference encoder), lowers a level by one, or drops it, when the
// bits saved are worth more than the distortion added: per block, in the coder's reverse scan
// order, each nonzero level l chooses among l, l - 1 (and 0 for l <= 2) the one of least
//   (|c| / step - l')^2 + lambda * bits(l'),
// distortion in units of step^2 (the DCT is orthonormal, so it is the grid's squared error) and
// bits estimated from the coefficient coder's adaptive CDFs as they stand before the block: the
// level's own symbols and those of the lower frequencies whose contexts it changes. The block's
// last level may also be dropped (a shorter end-of-block, evaluated exactly), and the whole block
// when coding it costs more than it gives. The decoder is unchanged: the stream holds levels.
// Greedy per coefficient; effects on later blocks (adaptation, neighbour contexts) are ignored.
//
// lambda is in squared steps per bit: at high rate a uniform quantizer's own trade is
// 2 ln 2 * step^2 / 12, about 0.12, so values around 0.1 leave most levels alone.
#ifndef ECRF_ENCODER_COEF_RDOQ_H_
#define ECRF_ENCODER_COEF_RDOQ_H_

#include <cstddef>
#include <cstdint>

#include "encoder/grid_dct.h"
#include "format/coefficients/coef_contexts.h"

namespace ecrf {
namespace encoder {

// Beyond this a level costs more in distortion than any bit count it could save is worth.
inline constexpr float kMaxRdoqLambda = 10.f;

struct RdoqOptions {
  double lambda = 0.0;           // squared steps per bit; 0: plain rounding
  double rounding_offset = 0.5;  // the starting levels (encoder/coef_quantizer.h)
  int32_t max_abs = 127;         // levels are clipped to [-max_abs, max_abs] first
  CoefContextSet set = CoefContextSet::kNeighbour;  // the contexts whose costs decide
};

// levels[layout.num_coeffs()] for the coefficients of one tensor (block order, as ForwardBlocks
// writes them) quantized with `step`. Deterministic: a pure function of its inputs. Returns how
// many levels were clipped to max_abs. Throws std::invalid_argument on an invalid layout.
size_t RdoqLevels(const float* coeffs, const GridBlockLayout& layout, double step,
                  const RdoqOptions& options, int32_t* levels);

}  // namespace encoder
}  // namespace ecrf

#endif  // ECRF_ENCODER_COEF_RDOQ_H_
