#include <cstdlib>

#include "format/coefficients/coef_coder.h"

namespace ecrf {
namespace {

uint32_t Magnitude(int32_t value) {
  return value < 0 ? 0u - static_cast<uint32_t>(value) : static_cast<uint32_t>(value);
}

void EncodeEob(RangeEncoder& encoder, CoefContexts& contexts, int eob) {
  const int eob_class = EobClass(eob);
  if (contexts.num_eob_classes > 1) {
    encoder.EncodeSymbol(eob_class, contexts.eob_class_cdf, contexts.num_eob_classes);
  }
  if (eob_class < 2) return;
  const int offset_bits = eob_class - 1;
  const uint32_t offset = static_cast<uint32_t>(eob - (1 << offset_bits) - 1);
  encoder.EncodeBool((offset >> (offset_bits - 1)) & 1, contexts.eob_extra_cdf[eob_class]);
  encoder.EncodeBypass(offset, offset_bits - 1);
}

// Everything of a level above the base symbol, then the sign.
void EncodeLevelTail(RangeEncoder& encoder, CoefContexts& contexts, const uint8_t* level_slot,
                     const ScanEntry& entry, uint32_t level, int32_t value) {
  if (level >= kBaseLevelCap) {
    uint16_t* cdf = contexts.range_cdf[RangeContext(level_slot, contexts.scan, entry)];
    uint32_t coded = kBaseLevelCap;
    for (int i = 0; i < kMaxRangeSymbols; ++i) {
      const uint32_t step = MinU32(level - coded, kRangeSymbols - 1);
      encoder.EncodeSymbol(static_cast<int>(step), cdf, kRangeSymbols);
      coded += step;
      if (step < kRangeSymbols - 1) break;
    }
    if (coded == kEscapeLevel) {
      const uint32_t remainder = level - kEscapeLevel;
      encoder.EncodeGolomb(remainder, EscapeGolombOrder(contexts.escape_stat));
      UpdateEscapeStat(&contexts.escape_stat, remainder);
    }
  }
  encoder.EncodeBypass(value < 0 ? 1 : 0, 1);
}

}  // namespace

void EncodeCoefBlock(RangeEncoder& encoder, CoefContexts& contexts, const int32_t* coeffs) {
  const ScanEntry* entries = contexts.scan.entries.data();
  int eob = contexts.scan.shape.Volume();
  while (eob > 0 && coeffs[entries[eob - 1].raster] == 0) --eob;

  const int coded = eob > 0;
  const bool neighbour = contexts.set == CoefContextSet::kNeighbour;
  if (neighbour) contexts.BeginNeighbourBlock();
  encoder.EncodeBool(coded, contexts.coded_cdf[contexts.prev_coded[0] + contexts.prev_coded[1]]);
  contexts.prev_coded[1] = contexts.prev_coded[0];
  contexts.prev_coded[0] = static_cast<uint8_t>(coded);
  if (!coded) {
    if (neighbour) contexts.EndNeighbourBlock(coeffs, 0);
    return;
  }
  EncodeEob(encoder, contexts, eob);

  uint8_t* levels = contexts.levels.data();
  const CoefContextSet set = contexts.set;
  const int s1 = contexts.scan.padded_stride1, s0 = contexts.scan.padded_stride0;
  const NeighbourLevels neighbours(contexts);
  for (int s = eob - 1; s >= 0; --s) {
    const ScanEntry& entry = entries[s];
    const int32_t value = coeffs[entry.raster];
    const uint32_t level = Magnitude(value);
    uint8_t* slot = levels + entry.padded;
    const uint32_t base = MinU32(level, kBaseLevelCap);
    if (s == eob - 1) {
      encoder.EncodeSymbol(static_cast<int>(base) - 1, contexts.last_base_cdf[entry.base_band],
                           kLastBaseSymbols);
    } else {
      encoder.EncodeSymbol(static_cast<int>(base),
                           contexts.base_cdf[BaseContext(slot, set, s1, s0, neighbours, entry)],
                           kBaseSymbols);
    }
    if (level != 0) EncodeLevelTail(encoder, contexts, slot, entry, level, value);
    *slot = static_cast<uint8_t>(MinU32(level, kEscapeLevel));
  }
  for (int s = 0; s < eob; ++s) levels[entries[s].padded] = 0;
  if (neighbour) contexts.EndNeighbourBlock(coeffs, eob);
}

}  // namespace ecrf
