// The adaptive state of the coefficient coder for one block shape, and the context derivations
// that encoder and decoder must share exactly (SPEC.md section 4, "Contexts").
#ifndef ECRF_FORMAT_COEFFICIENTS_COEF_CONTEXTS_H_
#define ECRF_FORMAT_COEFFICIENTS_COEF_CONTEXTS_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "format/coefficients/coef_scan.h"
#include "format/status.h"

namespace ecrf {

constexpr int kCodedFlagContexts = 3;     // how many of the previous two blocks were coded
constexpr int kMaxEobClasses = 13;        // eob in [1, 4096]
constexpr int kBaseSymbols = 4;           // base level 0, 1, 2 or >= 3
constexpr int kLastBaseSymbols = 3;       // base level of the last coefficient: 1, 2 or >= 3
constexpr int kRangeSymbols = 4;          // each adds 0..3; 3 means "more follows"
constexpr int kMaxRangeSymbols = 4;       // range symbols take a level from 3 up to 15
constexpr int kBaseMagContexts = 5;       // narrow set: three neighbours
constexpr int kWideBaseMagContexts = 11;  // wide set: nine neighbours
constexpr int kRangeMagContexts = 7;
constexpr uint32_t kBaseLevelCap = 3;
constexpr uint32_t kEscapeLevel = 15;  // levels >= 15 add an Exp-Golomb remainder
constexpr int kMaxEscapeStat = 63;

// Which neighbours select the CDF of a base level (SPEC.md 4.7); the value is the `contexts` byte
// of a COEF chunk (6.4.2). Narrow, the only set of streams 1.0-1.3: the three neighbours one
// frequency step higher. Wide (1.4): also the six two steps higher. A quantized feature block's
// significance is told by a wider neighbourhood; on trained chair grids the wide set saves
// 2-3.5% of the coefficient bytes.
//
// Neighbour (1.5): the wide neighbourhood plus the capped levels at the same position in the
// three blocks of the chunk coded just before it along each block axis (the previous channel
// block, the block above and the block to the left). Feature planes are smooth across block
// borders and their components share the scene's geometry, so a coefficient is more likely
// significant where its neighbours' co-located ones were: on a trained chair grid this codes
// 1.7% fewer coefficient bytes than the wide set (SPEC.md 4.7, docs/results.md). The block's
// coded flag, eob and level tails gained nothing from the neighbours there, so they keep the
// contexts of the other sets.
enum class CoefContextSet : uint8_t { kNarrow = 0, kWide = 1, kNeighbour = 2 };
constexpr uint8_t kMaxCoefContextSet = 2;
// The container minor version a stream with a wide COEF chunk needs at least (SPEC.md 2.1).
constexpr uint8_t kWideContextsMinVersionMinor = 4;
// ... and one with a neighbour COEF chunk.
constexpr uint8_t kNeighbourContextsMinVersionMinor = 5;

inline uint8_t CoefContextSetMinVersionMinor(CoefContextSet set) {
  return set == CoefContextSet::kNarrow ? 0
         : set == CoefContextSet::kWide ? kWideContextsMinVersionMinor
                                        : kNeighbourContextsMinVersionMinor;
}

// Neighbour set: a base level's class is WideMag plus the neighbour sum (each capped level at most
// 3), capped at 15.
constexpr int kNeighbourBaseMagContexts = 16;
constexpr uint8_t kNeighbourLevelCap = 3;

// All CDFs of one tensor chunk and one block shape. Init() once per shape, Reset() at the start
// of each chunk; the members are the state the block coder reads and adapts.
struct CoefContexts {
  // kErrInvalidArgument for an invalid shape. Allocates the scan table and level map.
  Status Init(const BlockShape& shape, CoefContextSet set = CoefContextSet::kWide);
  // The neighbour set also needs the chunk's block grid (blocks along each block axis, >= 1)
  // for its per-chunk memory of one block per (b1, b2) column: NeighbourBytes() (blocks[1] *
  // blocks[2] * (Volume() + 2)); kErrLimit above max_bytes.
  Status Init(const BlockShape& shape, CoefContextSet set, const int blocks[3], size_t max_bytes);
  // Back to the initial state of a chunk: uniform CDFs, no history.
  void Reset();

  // Neighbour set: called by the block coder before each block (raster order over the block
  // grid) to point nbr[] at the block's neighbours, and after it with the block's levels.
  void BeginNeighbourBlock();
  void EndNeighbourBlock(const int32_t* coeffs, int eob);

  ScanTable scan;
  CoefContextSet set = CoefContextSet::kWide;
  int num_eob_classes = 0;         // log2(volume) + 1
  std::vector<uint8_t> levels;     // padded map of min(level, 15); all zero between blocks
  uint8_t prev_coded[2] = {0, 0};  // coded flags of the previous two blocks, latest first
  int escape_stat = 0;             // Rice-style statistic choosing the Exp-Golomb order

  // Neighbour set only. Slot (b1, b2) holds min(level, 3) of the latest block coded at that
  // (b1, b2) in raster order (the previous channel block until the current one replaces it)
  // and its eob; nbr[] point at the slots of the previous channel block, the block above and the
  // block to the left of the current block, or at zero_slot where there is none.
  int block_grid[3] = {0, 0, 0};
  uint64_t next_block = 0;
  std::vector<uint8_t> slot_levels;
  std::vector<uint16_t> slot_eob;
  std::vector<uint8_t> zero_slot;
  const uint8_t* nbr[3] = {nullptr, nullptr, nullptr};
  size_t current_slot = 0;

  uint16_t coded_cdf[kCodedFlagContexts][3];
  uint16_t eob_class_cdf[kMaxEobClasses + 1];
  uint16_t eob_extra_cdf[kMaxEobClasses][3];
  uint16_t last_base_cdf[kNumBaseBands][kLastBaseSymbols + 1];
  // Per band: narrow 5, wide 11, neighbour 16 classes.
  uint16_t base_cdf[kNumBaseBands * kNeighbourBaseMagContexts][kBaseSymbols + 1];
  uint16_t range_cdf[kNumRangeBands * kRangeMagContexts][kRangeSymbols + 1];
};

// Bytes of the neighbour set's per-chunk memory for a block grid.
uint64_t NeighbourBytes(const BlockShape& shape, const int blocks[3]);

// eob class: 0 for eob 1, else 1 + FloorLog2(eob - 1); class c >= 2 has c - 1 offset bits.
inline int EobClass(int eob) {
  return eob == 1 ? 0 : 32 - __builtin_clz(static_cast<uint32_t>(eob - 1));
}

inline uint32_t MinU32(uint32_t a, uint32_t b) { return a < b ? a : b; }

// The block's neighbour levels, copied out of CoefContexts so that the coder's loop keeps them
// in registers (its byte stores to the level map may alias any member).
struct NeighbourLevels {
  const uint8_t* previous_channel;  // all three null outside the neighbour set
  const uint8_t* above;
  const uint8_t* left;
  explicit NeighbourLevels(const CoefContexts& contexts)
      : previous_channel(contexts.nbr[0]), above(contexts.nbr[1]), left(contexts.nbr[2]) {}
  // The sum of the capped levels at raster position `raster` of the three blocks (0..9).
  uint32_t Sum(int raster) const {
    return uint32_t{previous_channel[raster]} + above[raster] + left[raster];
  }
};

// `level` points at the coefficient's slot in the padded level map. Every neighbour read here
// has a higher frequency sum, so it was coded before the coefficient in reverse scan order.
// `set` and the strides are the contexts' (passed by value for the same reason).
inline int BaseContext(const uint8_t* level, CoefContextSet set, int s1, int s0,
                       const NeighbourLevels& neighbours, const ScanEntry& entry) {
  uint32_t mag = MinU32(level[1], kBaseLevelCap) + MinU32(level[s1], kBaseLevelCap) +
                 MinU32(level[s0], kBaseLevelCap);
  if (set == CoefContextSet::kNarrow) {
    return entry.base_band * kBaseMagContexts +
           static_cast<int>(MinU32((mag + 1) >> 1, kBaseMagContexts - 1));
  }
  mag += MinU32(level[2], kBaseLevelCap) + MinU32(level[2 * s1], kBaseLevelCap) +
         MinU32(level[2 * s0], kBaseLevelCap) + MinU32(level[s1 + 1], kBaseLevelCap) +
         MinU32(level[s0 + 1], kBaseLevelCap) + MinU32(level[s0 + s1], kBaseLevelCap);
  if (set == CoefContextSet::kWide) {
    return entry.base_band * kWideBaseMagContexts +
           static_cast<int>(MinU32(mag, kWideBaseMagContexts - 1));
  }
  mag += neighbours.Sum(entry.raster);
  return entry.base_band * kNeighbourBaseMagContexts +
         static_cast<int>(MinU32(mag, kNeighbourBaseMagContexts - 1));
}

inline int RangeContext(const uint8_t* level, const ScanTable& scan, const ScanEntry& entry) {
  const uint32_t mag = uint32_t{level[1]} + level[scan.padded_stride1] + level[scan.padded_stride0];
  return entry.range_band * kRangeMagContexts +
         static_cast<int>(MinU32((mag + 1) >> 1, kRangeMagContexts - 1));
}

inline int EscapeGolombOrder(int escape_stat) { return escape_stat >> 2; }

// HEVC's persistent Rice adaptation: grow the order after large remainders, shrink it after
// small ones.
inline void UpdateEscapeStat(int* escape_stat, uint32_t remainder) {
  const int k = EscapeGolombOrder(*escape_stat);
  if (remainder >= (3u << k)) {
    if (*escape_stat < kMaxEscapeStat) ++*escape_stat;
  } else if (2 * remainder < (1u << k) && *escape_stat > 0) {
    --*escape_stat;
  }
}

}  // namespace ecrf

#endif  // ECRF_FORMAT_COEFFICIENTS_COEF_CONTEXTS_H_
