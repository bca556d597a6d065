// Adaptive multi-symbol range coder (the entropy coder of every ecrf coefficient stream).
//
// The arithmetic is the AV1/Daala od_ec design: a 16-bit range, 15-bit inverse CDFs whose
// probabilities are floored by kCdfMinProb so no symbol ever gets an empty interval, and
// count-based adaptation (fast while a context is young, slower once it has seen 32 symbols).
// It was chosen because it is proven, needs only 32-bit integer arithmetic (the decoder runs
// on microcontrollers and WASM) and is specified bit-exactly in SPEC.md section 3.
//
// CDF layout: a context for an alphabet of N symbols (2 <= N <= 16) is uint16_t cdf[N + 1].
// cdf[i] = 32768 * P(symbol > i) ("inverse CDF"), so cdf[N - 1] is always 0, and cdf[N] is
// the adaptation counter (starts at 0, saturates at 32).
#ifndef ECRF_FORMAT_ENTROPY_RANGE_CODER_H_
#define ECRF_FORMAT_ENTROPY_RANGE_CODER_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "format/status.h"

namespace ecrf {

constexpr uint32_t kCdfProbTop = 32768;  // probabilities are 15-bit fixed point
constexpr int kCdfProbShift = 6;         // CDFs enter the range split with 9 bits
constexpr uint32_t kCdfMinProb = 4;      // per-symbol floor, in range units
constexpr int kMaxSymbols = 16;
constexpr int kMaxBypassBits = 32;
// Exp-Golomb escapes carry values in [0, kMaxGolombValue] with order k in [0, kMaxGolombK];
// a decoder rejects longer codes, so a corrupt stream cannot make it loop or overflow.
constexpr uint32_t kMaxGolombValue = 0x7FFFFFFFu;
constexpr int kMaxGolombK = 30;

// Sets cdf[0..num_symbols] to the uniform distribution with a fresh counter:
// cdf[i] = (32768 * (num_symbols - 1 - i)) / num_symbols.
void InitUniformCdf(uint16_t* cdf, int num_symbols);

// Moves the CDF towards `symbol` (AV1 update_cdf). Shared by encoder and decoder, so both see
// the same probabilities after every symbol.
inline void AdaptCdf(uint16_t* cdf, int symbol, int num_symbols) {
  const uint32_t count = cdf[num_symbols];
  const int rate = 3 + (count > 15) + (count > 31) + (num_symbols > 3 ? 2 : 1);
  // Two branch-free loops (symbols below / from the coded one) that compilers vectorise.
  for (int i = 0; i < symbol; ++i) {
    cdf[i] = static_cast<uint16_t>(cdf[i] + ((kCdfProbTop - cdf[i]) >> rate));
  }
  for (int i = symbol; i < num_symbols - 1; ++i) {
    cdf[i] = static_cast<uint16_t>(cdf[i] - (cdf[i] >> rate));
  }
  cdf[num_symbols] = static_cast<uint16_t>(count + (count < 32));
}

// Upper end of the sub-interval boundary for `symbol` (the decoder's "cur" value): the part of
// the range that belongs to symbols greater than `symbol`.
inline uint32_t RangeSplit(uint32_t rng, uint32_t icdf, int symbol, int num_symbols) {
  return (((rng >> 8) * (icdf >> kCdfProbShift)) >> 1) +
         kCdfMinProb * static_cast<uint32_t>(num_symbols - 1 - symbol);
}

class RangeEncoder {
 public:
  RangeEncoder() = default;

  // Codes symbol in [0, num_symbols) with cdf (num_symbols + 1 entries) and adapts cdf.
  void EncodeSymbol(int symbol, uint16_t* cdf, int num_symbols);
  // Binary symbol with an adaptive cdf[3].
  void EncodeBool(int bit, uint16_t* cdf) { EncodeSymbol(bit != 0, cdf, 2); }
  // Equiprobable bits, most significant first; num_bits in [0, 32].
  void EncodeBypass(uint32_t value, int num_bits);
  // Exp-Golomb of order k in bypass bits; value <= kMaxGolombValue, k in [0, kMaxGolombK].
  void EncodeGolomb(uint32_t value, int k);

  // Bits produced so far if the stream ended now (before byte rounding); for rate estimates.
  uint64_t BitCount() const { return total_shift_; }

  // Flushes and returns the stream: exactly ceil(BitCount() / 8) bytes, the shortest length
  // the decoder's end-of-stream check accepts. The encoder is reset afterwards.
  std::vector<uint8_t> Finish();

 private:
  // Keeps the part [rng - upper, rng - lower) of the current interval (offsets from its base),
  // where upper/lower are the decoder's split values around the coded symbol.
  void EncodeInterval(uint32_t upper, uint32_t lower);
  void EncodeBypassBit(int bit);
  void EmitSettledBytes();
  void PropagateCarry();

  std::vector<uint8_t> bytes_;
  uint64_t low_ = 0;          // bits of the interval base not yet moved to bytes_
  uint32_t rng_ = 0x8000;     // 16-bit range, normalised to [32768, 65535]
  int pending_bits_ = 15;     // width of low_ (position of its carry bit)
  uint64_t total_shift_ = 0;  // sum of all normalisation shifts
};

// Decoding never reads outside [data, data + size): bytes past the end read as zero. Errors are
// sticky (HasError() is a plain load, so hot loops can poll it per block, not per symbol); the
// values decoded after an error are unspecified but every call stays memory safe and bounded.
// Call Finish() after the last symbol: it also rejects streams the decoder read beyond their end.
class RangeDecoder {
 public:
  RangeDecoder(const uint8_t* data, size_t size);

  int DecodeSymbol(uint16_t* cdf, int num_symbols);
  int DecodeBool(uint16_t* cdf) { return DecodeSymbol(cdf, 2); }
  int DecodeBypassBit();
  uint32_t DecodeBypass(int num_bits);
  uint32_t DecodeGolomb(int k);

  bool HasError() const { return error_ != kOk; }
  // The sticky error as a Status: kErrCorrupt for an invalid escape code, kErrTruncated once
  // the decoder is certainly past the end; Ok otherwise.
  Status status() const;
  // status(), plus kErrTruncated if the symbols decoded so far need more bits than the stream
  // holds. Call after the last symbol of the stream.
  Status Finish() const;

 private:
  void Normalize(uint32_t dif, uint32_t rng);
  void Refill();
  void SetError(int code) {
    if (error_ == kOk) error_ = code;
  }

  // The window holds the inverted code bits: the top 16 bits are compared against the range,
  // the cnt_ bits below them are look-ahead, and all lower bits are ones.
  const uint8_t* pos_;
  const uint8_t* end_;
  uint32_t dif_;
  uint32_t rng_;
  int cnt_;
  int virtual_bytes_ = 0;  // zero bytes supplied past the end of the data
  int error_ = kOk;
};

inline int RangeDecoder::DecodeSymbol(uint16_t* cdf, int num_symbols) {
  const uint32_t value = dif_ >> 16;
  uint32_t upper;
  uint32_t lower = rng_;
  int symbol = -1;
  do {
    ++symbol;
    upper = lower;
    lower = RangeSplit(rng_, cdf[symbol], symbol, num_symbols);
  } while (value < lower);
  Normalize(dif_ - (lower << 16), upper - lower);
  AdaptCdf(cdf, symbol, num_symbols);
  return symbol;
}

inline int RangeDecoder::DecodeBypassBit() {
  // The fixed CDF {16384, 0}: RangeSplit reduces to a shift.
  const uint32_t split = ((rng_ >> 8) << 7) + kCdfMinProb;
  const uint32_t split_window = split << 16;
  if (dif_ >= split_window) {
    Normalize(dif_ - split_window, rng_ - split);
    return 0;
  }
  Normalize(dif_, split);
  return 1;
}

inline uint32_t RangeDecoder::DecodeBypass(int num_bits) {
  uint32_t value = 0;
  for (int i = 0; i < num_bits; ++i)
    value = (value << 1) | static_cast<uint32_t>(DecodeBypassBit());
  return value;
}

inline void RangeDecoder::Normalize(uint32_t dif, uint32_t rng) {
  const int shift = __builtin_clz(rng) - 16;  // rng is in [4, 65535]
  cnt_ -= shift;
  // Ones are the inverted form of bits not loaded yet; Refill XORs the real bits in.
  dif_ = (dif << shift) | ((1u << shift) - 1);
  rng_ = rng << shift;
  if (cnt_ < 0) Refill();
}

}  // namespace ecrf

#endif  // ECRF_FORMAT_ENTROPY_RANGE_CODER_H_
