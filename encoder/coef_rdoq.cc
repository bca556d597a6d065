#include "encoder/coef_rdoq.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "encoder/coef_quantizer.h"
#include "format/coefficients/coef_coder.h"
#include "format/entropy/range_coder.h"

namespace ecrf {
namespace encoder {
namespace {

// -log2(p / 32768) for p in [1, 32768]: the cost of a symbol in bits.
const std::vector<float>& BitsTable() {
  static const std::vector<float> table = [] {
    std::vector<float> t(kCdfProbTop + 1);
    t[0] = 15.f;  // never a coded symbol's probability; the floor keeps it finite
    for (uint32_t p = 1; p <= kCdfProbTop; ++p) {
      t[p] = static_cast<float>(-std::log2(double(p) / kCdfProbTop));
    }
    return t;
  }();
  return table;
}

inline float SymbolBits(const float* table, const uint16_t* cdf, int symbol) {
  const uint32_t above = symbol == 0 ? kCdfProbTop : cdf[symbol - 1];
  return table[above - cdf[symbol]];
}

inline float GolombBits(uint32_t value, int k) {
  const uint32_t prefix_value = (value >> k) + 1;
  return float(2 * (31 - __builtin_clz(prefix_value)) + 1 + k);
}

// The RD state of one block: current magnitudes by scan position, the padded level map the
// contexts read, and the coder's CDFs as they stand before the block (read only).
class BlockRd {
 public:
  BlockRd(const CoefContexts& contexts, const float* bits_table)
      : ctx_(contexts),
        bits_(bits_table),
        entries_(contexts.scan.entries.data()),
        volume_(contexts.scan.shape.Volume()),
        s1_(contexts.scan.padded_stride1),
        s0_(contexts.scan.padded_stride0),
        map_(size_t(contexts.scan.padded_volume), 0),
        scan_of_padded_(size_t(contexts.scan.padded_volume), -1),
        mag_(size_t(volume_), 0),
        u_(size_t(volume_), 0.0) {
    for (int s = 0; s < volume_; ++s) scan_of_padded_[entries_[s].padded] = s;
    // The positions whose base context reads a coefficient are the coefficient's padded index
    // minus these (coef_contexts.h BaseContext); the first three also carry range contexts.
    const int offsets[9] = {1, s1_, s0_, 2, 2 * s1_, 2 * s0_, s1_ + 1, s0_ + 1, s0_ + s1_};
    std::copy(offsets, offsets + 9, offsets_);
  }

  // Decides the levels of one block: quotients |c| / step in raster order, signs kept by the
  // caller. mag_out (raster order) receives the magnitudes.
  void Decide(const double* quotient, const uint32_t* start, double lambda, uint32_t* mag_out) {
    const NeighbourLevels neighbours(ctx_);
    neighbours_ = &neighbours;
    int eob = 0;
    for (int s = 0; s < volume_; ++s) {
      const int raster = entries_[s].raster;
      u_[s] = quotient[raster];
      mag_[s] = start[raster];
      map_[entries_[s].padded] = static_cast<uint8_t>(MinU32(mag_[s], kEscapeLevel));
      if (mag_[s] != 0) eob = s + 1;
    }
    int exact_evaluations = 0;
    for (int s = eob - 1; s >= 0 && eob > 0; --s) {
      const uint32_t level = mag_[s];
      if (level == 0) continue;
      const bool last = s == eob - 1;
      uint32_t candidates[3];
      int num_candidates = 0;
      candidates[num_candidates++] = level;
      if (level >= 2) candidates[num_candidates++] = level - 1;
      if (!last && level <= 2) candidates[num_candidates++] = 0;
      // The lower positions whose symbols the choice can change (every position below eob is
      // coded, zeros too). Base contexts see levels capped at 3 and range contexts (the first
      // three offsets, of levels >= 3) levels capped at 15, so from level 4 on only range
      // contexts differ between the candidates, and from 16 on nothing: the costs left out are
      // the same for every candidate.
      int affected[9];
      int num_affected = 0;
      if (level <= kEscapeLevel) {
        const int considered = level >= 4 ? 3 : 9;
        for (int k = 0; k < considered; ++k) {
          const int p = entries_[s].padded - offsets_[k];
          if (p < 0) continue;
          const int ps = scan_of_padded_[size_t(p)];
          if (ps >= 0 && (level < 4 || mag_[ps] >= kBaseLevelCap)) affected[num_affected++] = ps;
        }
      }
      uint32_t best = level;
      double best_cost = 0.0;
      for (int c = 0; c < num_candidates; ++c) {
        const uint32_t candidate = candidates[c];
        SetLevel(s, candidate);
        double bits = CoefBits(s, candidate, last);
        for (int i = 0; i < num_affected; ++i) {
          bits += CoefBits(affected[i], mag_[affected[i]], false);
        }
        const double d = u_[s] - double(candidate);
        const double cost = d * d + lambda * bits;
        if (c == 0 || cost < best_cost) {
          best = candidate;
          best_cost = cost;
        }
      }
      SetLevel(s, best);
      if (last && best == 1 && exact_evaluations < kMaxExactEvaluations) {
        // Dropping the last level moves the end of block: the bits of both blocks, exactly.
        ++exact_evaluations;
        int shorter = s;
        while (shorter > 0 && mag_[shorter - 1] == 0) --shorter;
        const double saved = DropLastBits(s, eob, shorter);
        SetLevel(s, 0);
        if (DistortionChange(s, 1) < lambda * saved) {
          eob = shorter;
        } else {
          SetLevel(s, 1);
        }
      }
    }
    // The whole block against not coding it, unless dropping it adds more distortion than 16
    // bits per coded position could be worth (far more than a block's symbols cost).
    if (eob > 0) {
      double added = 0.0;
      for (int s = 0; s < eob; ++s) added += DistortionChange(s, mag_[s]);
      if (added < lambda * (16.0 * eob + 64.0) &&
          added < BlockCost(eob, lambda) - lambda * SymbolBits(bits_, CodedCdf(), 0)) {
        for (int s = 0; s < eob; ++s) SetLevel(s, 0);
      }
    }
    for (int s = 0; s < volume_; ++s) {
      mag_out[entries_[s].raster] = mag_[s];
      map_[entries_[s].padded] = 0;
    }
  }

 private:
  static constexpr int kMaxExactEvaluations = 8;  // bounds the work of a block to O(8 eob)

  void SetLevel(int s, uint32_t level) {
    mag_[s] = level;
    map_[entries_[s].padded] = static_cast<uint8_t>(MinU32(level, kEscapeLevel));
  }

  const uint16_t* CodedCdf() const {
    return ctx_.coded_cdf[ctx_.prev_coded[0] + ctx_.prev_coded[1]];
  }

  // (u - 0)^2 - (u - level)^2: what zeroing the level at s adds.
  double DistortionChange(int s, uint32_t level) const {
    const double d = u_[s] - double(level);
    return u_[s] * u_[s] - d * d;
  }

  // The bits of the level at scan position s under the current map (EncodeCoefBlock's symbols).
  double CoefBits(int s, uint32_t level, bool last) const {
    const ScanEntry& e = entries_[s];
    const uint8_t* slot = map_.data() + e.padded;
    const uint32_t base = MinU32(level, kBaseLevelCap);
    double bits;
    if (last) {
      bits = SymbolBits(bits_, ctx_.last_base_cdf[e.base_band], int(base) - 1);
    } else {
      bits = SymbolBits(
          bits_, ctx_.base_cdf[BaseContext(slot, ctx_.set, s1_, s0_, *neighbours_, e)], int(base));
    }
    if (level == 0) return bits;
    bits += 1.0;  // the sign
    if (level >= kBaseLevelCap) {
      const uint16_t* cdf = ctx_.range_cdf[RangeContext(slot, ctx_.scan, e)];
      uint32_t coded = kBaseLevelCap;
      for (int i = 0; i < kMaxRangeSymbols; ++i) {
        const uint32_t step = MinU32(level - coded, kRangeSymbols - 1);
        bits += SymbolBits(bits_, cdf, int(step));
        coded += step;
        if (step < kRangeSymbols - 1) break;
      }
      if (coded == kEscapeLevel) {
        bits += GolombBits(level - kEscapeLevel, EscapeGolombOrder(ctx_.escape_stat));
      }
    }
    return bits;
  }

  double EobBits(int eob) const {
    const int eob_class = EobClass(eob);
    double bits = 0.0;
    if (ctx_.num_eob_classes > 1) bits += SymbolBits(bits_, ctx_.eob_class_cdf, eob_class);
    if (eob_class >= 2) {
      const int offset_bits = eob_class - 1;
      const uint32_t offset = static_cast<uint32_t>(eob - (1 << offset_bits) - 1);
      bits +=
          SymbolBits(bits_, ctx_.eob_extra_cdf[eob_class], int((offset >> (offset_bits - 1)) & 1));
      bits += offset_bits - 1;
    }
    return bits;
  }

  // Bits saved by dropping the last level (1, at s = eob - 1) so that the block ends at
  // `shorter`: its symbols, the zeros between, the eob, and the symbols below whose contexts read
  // it or that become the last. The map holds the level at s on entry.
  double DropLastBits(int s, int eob, int shorter) {
    double keep = EobBits(eob) + CoefBits(s, 1, true);
    for (int i = shorter; i < s; ++i) keep += CoefBits(i, 0, false);
    if (shorter == 0) {
      return keep + SymbolBits(bits_, CodedCdf(), 1) - SymbolBits(bits_, CodedCdf(), 0);
    }
    int changed[10];
    int num_changed = 0;
    changed[num_changed++] = shorter - 1;
    for (int off : offsets_) {
      const int p = entries_[s].padded - off;
      if (p < 0) continue;
      const int ps = scan_of_padded_[size_t(p)];
      if (ps >= 0 && ps < shorter - 1) changed[num_changed++] = ps;
    }
    for (int i = 0; i < num_changed; ++i) keep += CoefBits(changed[i], mag_[changed[i]], false);
    SetLevel(s, 0);
    double drop = EobBits(shorter);
    for (int i = 0; i < num_changed; ++i) {
      drop += CoefBits(changed[i], mag_[changed[i]], changed[i] == shorter - 1);
    }
    SetLevel(s, 1);
    return keep - drop;
  }

  // lambda * bits of the block with end of block `eob` (levels beyond it must be zero).
  double BlockCost(int eob, double lambda) const {
    if (eob == 0) return lambda * SymbolBits(bits_, CodedCdf(), 0);
    double bits = SymbolBits(bits_, CodedCdf(), 1) + EobBits(eob);
    for (int s = 0; s < eob; ++s) bits += CoefBits(s, mag_[s], s == eob - 1);
    return lambda * bits;
  }

  const CoefContexts& ctx_;
  const float* bits_;
  const ScanEntry* entries_;
  const int volume_, s1_, s0_;
  int offsets_[9];
  std::vector<uint8_t> map_;
  std::vector<int> scan_of_padded_;
  std::vector<uint32_t> mag_;
  std::vector<double> u_;
  const NeighbourLevels* neighbours_ = nullptr;
};

}  // namespace

size_t RdoqLevels(const float* coeffs, const GridBlockLayout& layout, double step,
                  const RdoqOptions& options, int32_t* levels) {
  const int volume = layout.block_volume();
  const size_t n = layout.num_coeffs();
  size_t clipped = 0;
  for (size_t i = 0; i < n; ++i) {
    const double level = QuantizeLevel(double(coeffs[i]), step, options.rounding_offset);
    clipped += std::fabs(level) > options.max_abs;
    levels[i] =
        int32_t(std::max<double>(-options.max_abs, std::min<double>(options.max_abs, level)));
  }
  if (!(options.lambda > 0.0)) return clipped;

  CoefContexts contexts;
  const Status st = contexts.Init(BlockShape{layout.block[0], layout.block[1], layout.block[2]},
                                  options.set, layout.blocks, static_cast<size_t>(-1));
  if (!st.ok()) throw std::invalid_argument(st.message());
  RangeEncoder adapt;  // codes the chosen levels so the CDFs evolve as the encoder's will
  BlockRd rd(contexts, BitsTable().data());
  const size_t block_volume = static_cast<size_t>(volume);
  std::vector<double> quotient(block_volume);
  std::vector<uint32_t> start(block_volume), chosen(block_volume);
  const bool neighbour = options.set == CoefContextSet::kNeighbour;
  for (int b = 0; b < layout.num_blocks(); ++b) {
    int32_t* q = levels + size_t(b) * volume;
    const float* c = coeffs + size_t(b) * volume;
    bool any = false;
    for (int i = 0; i < volume; ++i) {
      quotient[i] = std::fabs(double(c[i])) / step;
      start[i] = q[i] < 0 ? uint32_t(-int64_t(q[i])) : uint32_t(q[i]);
      any |= q[i] != 0;
    }
    if (any) {
      // The neighbour set's block pointers, as EncodeCoefBlock will set them (then undone).
      if (neighbour) contexts.BeginNeighbourBlock();
      rd.Decide(quotient.data(), start.data(), options.lambda, chosen.data());
      if (neighbour) --contexts.next_block;
      for (int i = 0; i < volume; ++i) q[i] = c[i] < 0 ? -int32_t(chosen[i]) : int32_t(chosen[i]);
    }
    EncodeCoefBlock(adapt, contexts, q);
  }
  return clipped;
}

}  // namespace encoder
}  // namespace ecrf
