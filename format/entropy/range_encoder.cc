#include <cassert>

#include "format/entropy/range_coder.h"

namespace ecrf {

void RangeEncoder::EncodeSymbol(int symbol, uint16_t* cdf, int num_symbols) {
  assert(symbol >= 0 && symbol < num_symbols && num_symbols >= 2 && num_symbols <= kMaxSymbols);
  const uint32_t upper =
      symbol == 0 ? rng_ : RangeSplit(rng_, cdf[symbol - 1], symbol - 1, num_symbols);
  const uint32_t lower = RangeSplit(rng_, cdf[symbol], symbol, num_symbols);
  EncodeInterval(upper, lower);
  AdaptCdf(cdf, symbol, num_symbols);
}

void RangeEncoder::EncodeBypassBit(int bit) {
  const uint32_t split = ((rng_ >> 8) << 7) + kCdfMinProb;
  if (bit) {
    EncodeInterval(split, 0);
  } else {
    EncodeInterval(rng_, split);
  }
}

void RangeEncoder::EncodeBypass(uint32_t value, int num_bits) {
  assert(num_bits >= 0 && num_bits <= kMaxBypassBits);
  for (int i = num_bits - 1; i >= 0; --i) EncodeBypassBit((value >> i) & 1);
}

void RangeEncoder::EncodeGolomb(uint32_t value, int k) {
  assert(value <= kMaxGolombValue && k >= 0 && k <= kMaxGolombK);
  const uint32_t prefix_value = (value >> k) + 1;  // <= 2^31, so its bit length is <= 32
  const int length = 31 - __builtin_clz(prefix_value);
  EncodeBypass(0, length);
  EncodeBypass(prefix_value, length + 1);  // its leading one ends the run of zeros
  EncodeBypass(value & ((uint32_t{1} << k) - 1), k);
}

void RangeEncoder::EncodeInterval(uint32_t upper, uint32_t lower) {
  low_ += rng_ - upper;
  const uint32_t rng = upper - lower;
  const int shift = __builtin_clz(rng) - 16;
  rng_ = rng << shift;
  low_ <<= shift;
  pending_bits_ += shift;
  total_shift_ += static_cast<uint64_t>(shift);
  if (pending_bits_ >= 24) EmitSettledBytes();
}

// Moves whole bytes from the top of low_ to the output while keeping at least 16 bits, enough
// for the next interval update; later additions reach emitted bytes only as a carry.
void RangeEncoder::EmitSettledBytes() {
  while (pending_bits_ >= 24) {
    if (low_ >> pending_bits_) {
      PropagateCarry();
      low_ &= (uint64_t{1} << pending_bits_) - 1;
    }
    pending_bits_ -= 8;
    bytes_.push_back(static_cast<uint8_t>(low_ >> pending_bits_));
    low_ &= (uint64_t{1} << pending_bits_) - 1;
  }
}

// The interval never leaves [0, 1), so a carry always stops inside the emitted bytes.
void RangeEncoder::PropagateCarry() {
  for (size_t i = bytes_.size(); i-- > 0;) {
    if (++bytes_[i] != 0) return;
  }
}

std::vector<uint8_t> RangeEncoder::Finish() {
  // The decoder looks 15 bits past the last normalisation, so any code value in the interval
  // whose low 15 bits are zero needs only BitCount() bits; choose the smallest such value.
  low_ = (low_ + 0x7FFF) & ~uint64_t{0x7FFF};
  if (low_ >> pending_bits_) {
    PropagateCarry();
    low_ &= (uint64_t{1} << pending_bits_) - 1;
  }
  for (int remaining = pending_bits_ - 15; remaining > 0; remaining -= 8) {
    pending_bits_ -= 8;
    bytes_.push_back(static_cast<uint8_t>(low_ >> pending_bits_));
    low_ &= (uint64_t{1} << pending_bits_) - 1;
  }
  std::vector<uint8_t> out;
  out.swap(bytes_);
  *this = RangeEncoder();
  return out;
}

}  // namespace ecrf
