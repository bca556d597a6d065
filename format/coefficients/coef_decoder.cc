#include <cstring>

#include "format/coefficients/coef_coder.h"

namespace ecrf {
namespace {

int DecodeEob(RangeDecoder& decoder, CoefContexts& contexts) {
  const int eob_class = contexts.num_eob_classes > 1
                            ? decoder.DecodeSymbol(contexts.eob_class_cdf, contexts.num_eob_classes)
                            : 0;
  if (eob_class < 2) return eob_class + 1;
  const int offset_bits = eob_class - 1;
  uint32_t offset = static_cast<uint32_t>(decoder.DecodeBool(contexts.eob_extra_cdf[eob_class]))
                    << (offset_bits - 1);
  offset |= decoder.DecodeBypass(offset_bits - 1);
  return (1 << offset_bits) + 1 + static_cast<int>(offset);  // <= 2^eob_class <= volume
}

// Everything of a level above the base symbol (called for base level 3 only).
uint32_t DecodeLevelTail(RangeDecoder& decoder, CoefContexts& contexts, const uint8_t* level_slot,
                         const ScanEntry& entry) {
  uint16_t* cdf = contexts.range_cdf[RangeContext(level_slot, contexts.scan, entry)];
  uint32_t level = kBaseLevelCap;
  for (int i = 0; i < kMaxRangeSymbols; ++i) {
    const int step = decoder.DecodeSymbol(cdf, kRangeSymbols);
    level += static_cast<uint32_t>(step);
    if (step < kRangeSymbols - 1) return level;
  }
  const uint32_t remainder = decoder.DecodeGolomb(EscapeGolombOrder(contexts.escape_stat));
  UpdateEscapeStat(&contexts.escape_stat, remainder);
  return level + remainder;  // remainder < 2^31, no overflow
}

}  // namespace

Status DecodeCoefBlock(RangeDecoder& decoder, CoefContexts& contexts, int32_t max_abs,
                       int32_t* coeffs_out, int* eob_out) {
  ECRF_CHECK_OR_RETURN(max_abs >= 0, kErrInvalidArgument, "max_abs %d < 0", max_abs);
  const int volume = contexts.scan.shape.Volume();
  std::memset(coeffs_out, 0, sizeof(int32_t) * static_cast<size_t>(volume));
  if (eob_out != nullptr) *eob_out = 0;

  const bool neighbour = contexts.set == CoefContextSet::kNeighbour;
  if (neighbour) contexts.BeginNeighbourBlock();
  const int coded =
      decoder.DecodeBool(contexts.coded_cdf[contexts.prev_coded[0] + contexts.prev_coded[1]]);
  contexts.prev_coded[1] = contexts.prev_coded[0];
  contexts.prev_coded[0] = static_cast<uint8_t>(coded);
  if (!coded) {
    if (neighbour) contexts.EndNeighbourBlock(coeffs_out, 0);
    return decoder.status();
  }

  const int eob = DecodeEob(decoder, contexts);
  if (eob_out != nullptr) *eob_out = eob;
  const ScanEntry* entries = contexts.scan.entries.data();
  uint8_t* levels = contexts.levels.data();
  const CoefContextSet set = contexts.set;
  const int s1 = contexts.scan.padded_stride1, s0 = contexts.scan.padded_stride0;
  const NeighbourLevels neighbours(contexts);
  const uint32_t max_level = static_cast<uint32_t>(max_abs);
  Status status;
  for (int s = eob - 1; s >= 0; --s) {
    const ScanEntry& entry = entries[s];
    uint8_t* slot = levels + entry.padded;
    uint32_t level;
    if (s == eob - 1) {
      level = 1 + static_cast<uint32_t>(decoder.DecodeSymbol(
                      contexts.last_base_cdf[entry.base_band], kLastBaseSymbols));
    } else {
      level = static_cast<uint32_t>(decoder.DecodeSymbol(
          contexts.base_cdf[BaseContext(slot, set, s1, s0, neighbours, entry)], kBaseSymbols));
      if (level == 0) continue;  // the slot is already zero
    }
    if (level == kBaseLevelCap) level = DecodeLevelTail(decoder, contexts, slot, entry);
    if (level > max_level) {
      status = Status::Error(kErrCorrupt, "coefficient magnitude %u at scan index %d exceeds %d",
                             level, s, max_abs);
      break;
    }
    const int32_t magnitude = static_cast<int32_t>(level);
    coeffs_out[entry.raster] = decoder.DecodeBypassBit() ? -magnitude : magnitude;
    *slot = static_cast<uint8_t>(MinU32(level, kEscapeLevel));
  }
  for (int s = 0; s < eob; ++s) levels[entries[s].padded] = 0;
  if (!status.ok()) return status;
  if (neighbour) contexts.EndNeighbourBlock(coeffs_out, eob);
  return decoder.status();
}

}  // namespace ecrf
