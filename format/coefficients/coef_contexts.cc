#include "format/coefficients/coef_contexts.h"

#include <algorithm>

#include "format/entropy/range_coder.h"

namespace ecrf {

Status CoefContexts::Init(const BlockShape& shape, CoefContextSet context_set) {
  ECRF_CHECK_OR_RETURN(context_set != CoefContextSet::kNeighbour, kErrInvalidArgument,
                       "the neighbour context set needs the chunk's block grid");
  const int one[3] = {1, 1, 1};
  return Init(shape, context_set, one, 0);
}

Status CoefContexts::Init(const BlockShape& shape, CoefContextSet context_set, const int blocks[3],
                          size_t max_bytes) {
  ECRF_CHECK_OR_RETURN(IsValidBlockShape(shape), kErrInvalidArgument,
                       "invalid coefficient block shape %dx%dx%d", shape.n0, shape.n1, shape.n2);
  ECRF_CHECK_OR_RETURN(static_cast<uint8_t>(context_set) <= kMaxCoefContextSet, kErrInvalidArgument,
                       "unknown coefficient context set %u", static_cast<unsigned>(context_set));
  for (int a = 0; a < 3; ++a) {
    ECRF_CHECK_OR_RETURN(blocks[a] >= 1, kErrInvalidArgument, "block grid %dx%dx%d", blocks[0],
                         blocks[1], blocks[2]);
    block_grid[a] = blocks[a];
  }
  BuildScanTable(shape, &scan);
  set = context_set;
  num_eob_classes = 1 + (31 - __builtin_clz(static_cast<uint32_t>(shape.Volume())));
  levels.assign(static_cast<size_t>(scan.padded_volume), 0);
  slot_levels.clear();
  slot_eob.clear();
  zero_slot.clear();
  if (set == CoefContextSet::kNeighbour) {
    const uint64_t bytes = NeighbourBytes(shape, blocks);
    ECRF_CHECK_OR_RETURN(bytes <= max_bytes, kErrLimit,
                         "the neighbour contexts of a %dx%d block grid of %d coefficients need "
                         "%llu bytes, more than %zu",
                         blocks[1], blocks[2], shape.Volume(),
                         static_cast<unsigned long long>(bytes), max_bytes);
    const size_t slots = static_cast<size_t>(blocks[1]) * static_cast<size_t>(blocks[2]);
    slot_levels.assign(slots * static_cast<size_t>(shape.Volume()), 0);
    slot_eob.assign(slots, 0);
    zero_slot.assign(static_cast<size_t>(shape.Volume()), 0);
  }
  Reset();
  return Status::Ok();
}

uint64_t NeighbourBytes(const BlockShape& shape, const int blocks[3]) {
  return static_cast<uint64_t>(blocks[1]) * static_cast<uint64_t>(blocks[2]) *
         (static_cast<uint64_t>(shape.Volume()) + 2);
}

void CoefContexts::Reset() {
  std::fill(levels.begin(), levels.end(), uint8_t{0});
  std::fill(slot_levels.begin(), slot_levels.end(), uint8_t{0});
  std::fill(slot_eob.begin(), slot_eob.end(), uint16_t{0});
  next_block = 0;
  prev_coded[0] = prev_coded[1] = 0;
  escape_stat = 0;
  for (auto& cdf : coded_cdf) InitUniformCdf(cdf, 2);
  InitUniformCdf(eob_class_cdf, num_eob_classes > 1 ? num_eob_classes : 2);
  for (auto& cdf : eob_extra_cdf) InitUniformCdf(cdf, 2);
  for (auto& cdf : last_base_cdf) InitUniformCdf(cdf, kLastBaseSymbols);
  for (auto& cdf : base_cdf) InitUniformCdf(cdf, kBaseSymbols);
  for (auto& cdf : range_cdf) InitUniformCdf(cdf, kRangeSymbols);
}

void CoefContexts::BeginNeighbourBlock() {
  const uint64_t columns = static_cast<uint64_t>(block_grid[1]) * block_grid[2];
  // Blocks past the grid (a caller coding more blocks than it declared) wrap around: harmless,
  // deterministic, and never out of bounds.
  const uint64_t b = next_block++ % (columns * static_cast<uint64_t>(block_grid[0]));
  const int b2 = static_cast<int>(b % static_cast<uint64_t>(block_grid[2]));
  const int b1 = static_cast<int>((b / static_cast<uint64_t>(block_grid[2])) %
                                  static_cast<uint64_t>(block_grid[1]));
  const bool has[3] = {b >= columns, b1 > 0, b2 > 0};
  const size_t volume = static_cast<size_t>(scan.shape.Volume());
  current_slot = static_cast<size_t>(b % columns);
  const size_t slots[3] = {current_slot, current_slot - static_cast<size_t>(block_grid[2]),
                           current_slot - 1};
  for (int n = 0; n < 3; ++n) {
    nbr[n] = has[n] ? slot_levels.data() + slots[n] * volume : zero_slot.data();
  }
}

void CoefContexts::EndNeighbourBlock(const int32_t* coeffs, int eob) {
  const size_t volume = static_cast<size_t>(scan.shape.Volume());
  uint8_t* slot = slot_levels.data() + current_slot * volume;
  const ScanEntry* entries = scan.entries.data();
  // Scan positions at or beyond a slot's eob hold zeros: clear what the old block set beyond
  // the new eob, then write the new levels (work in proportion to the two eobs, not the volume).
  for (int s = eob; s < slot_eob[current_slot]; ++s) slot[entries[s].raster] = 0;
  for (int s = 0; s < eob; ++s) {
    const int32_t c = coeffs[entries[s].raster];
    const uint32_t magnitude = c < 0 ? 0u - static_cast<uint32_t>(c) : static_cast<uint32_t>(c);
    slot[entries[s].raster] = static_cast<uint8_t>(MinU32(magnitude, kNeighbourLevelCap));
  }
  slot_eob[current_slot] = static_cast<uint16_t>(eob);
}

}  // namespace ecrf
