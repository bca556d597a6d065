#include "format/entropy/range_coder.h"

namespace ecrf {

// Both coders start every adaptive CDF here; it lives with the decoder half, which the
// embeddable decoder has on its own.
void InitUniformCdf(uint16_t* cdf, int num_symbols) {
  for (int i = 0; i < num_symbols; ++i) {
    cdf[i] = static_cast<uint16_t>(kCdfProbTop * static_cast<uint32_t>(num_symbols - 1 - i) /
                                   static_cast<uint32_t>(num_symbols));
  }
  cdf[num_symbols] = 0;
}

RangeDecoder::RangeDecoder(const uint8_t* data, size_t size)
    : pos_(data),
      end_(data == nullptr ? data : data + size),
      dif_((1u << 31) - 1),
      rng_(0x8000),
      cnt_(-15) {
  Refill();
}

// Loads bytes below the look-ahead until at least 9 bits of look-ahead exist (cnt_ in [9, 16]).
void RangeDecoder::Refill() {
  int shift = 8 - cnt_;  // where the next byte goes: just below the current look-ahead
  uint32_t dif = dif_;
  if (end_ - pos_ >= 3) {
    do {
      dif ^= static_cast<uint32_t>(*pos_++) << shift;
      shift -= 8;
    } while (shift >= 0);
  } else {
    do {
      if (pos_ < end_) {
        dif ^= static_cast<uint32_t>(*pos_++) << shift;
      } else {
        ++virtual_bytes_;  // a zero byte: XOR with zero leaves the window unchanged
      }
      shift -= 8;
    } while (shift >= 0);
    // Five virtual bytes put the decoder at least 9 bits past the end: no valid stream does
    // that, so fail now rather than decode garbage until Finish().
    if (virtual_bytes_ >= 5) {
      SetError(kErrTruncated);
      virtual_bytes_ = 5;  // keep the counter bounded however long a caller keeps decoding
    }
  }
  dif_ = dif;
  cnt_ = 8 - shift;
}

uint32_t RangeDecoder::DecodeGolomb(int k) {
  if (k < 0 || k > kMaxGolombK) {
    SetError(kErrInvalidArgument);
    return 0;
  }
  int length = 0;
  while (DecodeBypassBit() == 0) {
    if (++length > 31 - k) {
      SetError(kErrCorrupt);
      return 0;
    }
  }
  const uint32_t prefix_value = (uint32_t{1} << length) | DecodeBypass(length);
  if (prefix_value - 1 > (kMaxGolombValue >> k)) {
    SetError(kErrCorrupt);
    return 0;
  }
  return ((prefix_value - 1) << k) | DecodeBypass(k);
}

Status RangeDecoder::status() const {
  if (error_ == kOk) return Status::Ok();
  if (error_ == kErrTruncated) {
    return Status::Error(kErrTruncated, "range decoder read past the end of its stream");
  }
  if (error_ == kErrInvalidArgument) {
    return Status::Error(kErrInvalidArgument, "range decoder: Golomb order out of range");
  }
  return Status::Error(error_, "range decoder: invalid Exp-Golomb escape code");
}

Status RangeDecoder::Finish() const {
  if (error_ != kOk) return status();
  // Bits consumed = 8 * bytes loaded - 15 - cnt_; they may exceed 8 * size only by the
  // 15-bit look-ahead that every stream ends with.
  if (8 * virtual_bytes_ > 15 + cnt_) {
    return Status::Error(kErrTruncated, "range decoder needs %d more bits than the stream holds",
                         8 * virtual_bytes_ - 15 - cnt_);
  }
  return Status::Ok();
}

}  // namespace ecrf
