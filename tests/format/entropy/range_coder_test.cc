#include "format/entropy/range_coder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace ecrf {
namespace {

// One coded event of a test stream, replayed on the decoder side.
struct Op {
  enum Kind { kSymbol, kBypass, kGolomb } kind;
  uint32_t value;
  int param;  // alphabet size, bit count or Golomb order
  int context;
};

struct Contexts {
  explicit Contexts(int count) : cdfs(static_cast<size_t>(count)) {}
  std::vector<std::vector<uint16_t>> cdfs;
  uint16_t* Get(int context, int num_symbols) {
    std::vector<uint16_t>& cdf = cdfs[static_cast<size_t>(context)];
    if (cdf.empty()) {
      cdf.resize(static_cast<size_t>(num_symbols) + 1);
      InitUniformCdf(cdf.data(), num_symbols);
    }
    return cdf.data();
  }
};

std::vector<uint8_t> EncodeOps(const std::vector<Op>& ops, int num_contexts) {
  Contexts contexts(num_contexts);
  RangeEncoder encoder;
  for (const Op& op : ops) {
    switch (op.kind) {
      case Op::kSymbol:
        encoder.EncodeSymbol(static_cast<int>(op.value), contexts.Get(op.context, op.param),
                             op.param);
        break;
      case Op::kBypass:
        encoder.EncodeBypass(op.value, op.param);
        break;
      case Op::kGolomb:
        encoder.EncodeGolomb(op.value, op.param);
        break;
    }
  }
  const uint64_t bits = encoder.BitCount();
  std::vector<uint8_t> bytes = encoder.Finish();
  EXPECT_EQ(bytes.size(), (bits + 7) / 8);
  return bytes;
}

// Decodes ops from bytes; returns the number of ops that decoded to the expected value.
size_t DecodeOps(const std::vector<Op>& ops, int num_contexts, const uint8_t* data, size_t size,
                 Status* finish) {
  Contexts contexts(num_contexts);
  RangeDecoder decoder(data, size);
  size_t matching = 0;
  bool all_match = true;
  for (const Op& op : ops) {
    uint32_t value = 0;
    switch (op.kind) {
      case Op::kSymbol:
        value = static_cast<uint32_t>(
            decoder.DecodeSymbol(contexts.Get(op.context, op.param), op.param));
        EXPECT_LT(value, static_cast<uint32_t>(op.param));
        break;
      case Op::kBypass:
        value = decoder.DecodeBypass(op.param);
        break;
      case Op::kGolomb:
        value = decoder.DecodeGolomb(op.param);
        break;
    }
    all_match = all_match && value == op.value;
    if (all_match) ++matching;
  }
  *finish = decoder.Finish();
  return matching;
}

void ExpectRoundTrip(const std::vector<Op>& ops, int num_contexts) {
  const std::vector<uint8_t> bytes = EncodeOps(ops, num_contexts);
  Status finish;
  EXPECT_EQ(DecodeOps(ops, num_contexts, bytes.data(), bytes.size(), &finish), ops.size());
  EXPECT_TRUE(finish.ok()) << finish.message();
}

std::vector<Op> RandomSymbols(std::mt19937& rng, int num_symbols, size_t count, bool skewed) {
  std::vector<double> weights(static_cast<size_t>(num_symbols));
  for (int i = 0; i < num_symbols; ++i) {
    weights[static_cast<size_t>(i)] = skewed ? 1.0 / (1 << std::min(2 * i, 30)) : 1.0;
  }
  std::discrete_distribution<int> dist(weights.begin(), weights.end());
  std::vector<Op> ops;
  for (size_t n = 0; n < count; ++n) {
    ops.push_back(
        {Op::kSymbol, static_cast<uint32_t>(dist(rng)), num_symbols, static_cast<int>(n % 3)});
  }
  return ops;
}

// A mix of everything the coder can code, with deterministic content.
std::vector<Op> MixedOps(uint32_t seed, size_t count) {
  std::mt19937 rng(seed);
  std::vector<Op> ops;
  for (size_t n = 0; n < count; ++n) {
    const uint32_t r = rng();
    const int num_symbols = 2 + static_cast<int>(r % 15);
    switch ((r >> 8) % 8) {
      case 0: {
        const int bits = static_cast<int>((r >> 12) % 33);
        const uint32_t value = bits == 0 ? 0 : static_cast<uint32_t>(rng() >> (32 - bits));
        ops.push_back({Op::kBypass, value, bits, 0});
        break;
      }
      case 1: {
        const int k = static_cast<int>((r >> 12) % 6);
        ops.push_back({Op::kGolomb, static_cast<uint32_t>(rng() >> (1 + (rng() % 31))), k, 0});
        break;
      }
      default: {
        // Skewed towards small symbols so the contexts adapt away from uniform.
        const uint32_t symbol = std::min<uint32_t>((rng() % 64) / (1 + (rng() % 16)),
                                                   static_cast<uint32_t>(num_symbols - 1));
        ops.push_back({Op::kSymbol, symbol, num_symbols, 100 + num_symbols});
      }
    }
  }
  return ops;
}

TEST(RangeCoderTest, UniformCdfIsDocumentedFormula) {
  uint16_t cdf[17];
  InitUniformCdf(cdf, 16);
  for (int i = 0; i < 16; ++i) EXPECT_EQ(cdf[i], 32768 * (15 - i) / 16);
  EXPECT_EQ(cdf[16], 0);
  InitUniformCdf(cdf, 3);
  EXPECT_EQ(cdf[0], 21845);
  EXPECT_EQ(cdf[1], 10922);
  EXPECT_EQ(cdf[2], 0);
  EXPECT_EQ(cdf[3], 0);
}

TEST(RangeCoderTest, AdaptationKeepsCdfValidAndCountsToThirtyTwo) {
  uint16_t cdf[5];
  InitUniformCdf(cdf, 4);
  for (int n = 0; n < 100000; ++n) {
    AdaptCdf(cdf, (n % 97 == 0) ? 3 : 0, 4);
    ASSERT_LT(cdf[0], 32768);
    ASSERT_GE(cdf[0], cdf[1]);
    ASSERT_GE(cdf[1], cdf[2]);
    ASSERT_EQ(cdf[3], 0);
  }
  EXPECT_EQ(cdf[4], 32);
  EXPECT_LT(cdf[0], 1000);  // symbol 0 dominates
}

TEST(RangeCoderTest, EmptyStreamIsZeroBytes) {
  RangeEncoder encoder;
  EXPECT_TRUE(encoder.Finish().empty());
  RangeDecoder decoder(nullptr, 0);
  EXPECT_TRUE(decoder.Finish().ok());
}

TEST(RangeCoderTest, RandomSymbolsAllAlphabetSizes) {
  std::mt19937 rng(1234);
  for (int num_symbols = 2; num_symbols <= kMaxSymbols; ++num_symbols) {
    for (bool skewed : {false, true}) {
      SCOPED_TRACE(testing::Message() << "N=" << num_symbols << " skewed=" << skewed);
      ExpectRoundTrip(RandomSymbols(rng, num_symbols, 20000, skewed), 3);
    }
  }
}

TEST(RangeCoderTest, CompressesNearEntropy) {
  // P(i) proportional to 4^-i over 8 symbols.
  double total = 0, entropy = 0;
  for (int i = 0; i < 8; ++i) total += 1.0 / (1 << (2 * i));
  for (int i = 0; i < 8; ++i) {
    const double p = 1.0 / (1 << (2 * i)) / total;
    entropy -= p * std::log2(p);
  }
  std::mt19937 rng(99);
  const std::vector<Op> ops = RandomSymbols(rng, 8, 100000, /*skewed=*/true);
  const std::vector<uint8_t> bytes = EncodeOps(ops, 3);
  const double bits_per_symbol = 8.0 * static_cast<double>(bytes.size()) / ops.size();
  EXPECT_LT(bits_per_symbol, 1.04 * entropy);
  EXPECT_GT(bits_per_symbol, 0.98 * entropy);
}

TEST(RangeCoderTest, AllZeroSymbolsAndBools) {
  std::vector<Op> ops;
  for (int n = 0; n < 50000; ++n) ops.push_back({Op::kSymbol, 0, 2 + n % 15, n % 15});
  ExpectRoundTrip(ops, 15);
}

TEST(RangeCoderTest, TenMillionEqualSymbolsCompressToAlmostNothing) {
  constexpr int kCount = 10000000;
  for (int symbol : {0, 15}) {
    uint16_t cdf[17];
    InitUniformCdf(cdf, 16);
    RangeEncoder encoder;
    for (int n = 0; n < kCount; ++n) encoder.EncodeSymbol(symbol, cdf, 16);
    const std::vector<uint8_t> bytes = encoder.Finish();
    // The probability floor bounds the cost at ~0.005 bits/symbol.
    EXPECT_LT(bytes.size() * 8.0 / kCount, 0.01) << bytes.size();
    InitUniformCdf(cdf, 16);
    RangeDecoder decoder(bytes.data(), bytes.size());
    int mismatches = 0;
    for (int n = 0; n < kCount; ++n) mismatches += decoder.DecodeSymbol(cdf, 16) != symbol;
    EXPECT_EQ(mismatches, 0);
    EXPECT_TRUE(decoder.Finish().ok());
  }
}

TEST(RangeCoderTest, BypassAllWidths) {
  std::mt19937 rng(7);
  std::vector<Op> ops;
  for (int bits = 0; bits <= kMaxBypassBits; ++bits) {
    const uint32_t max = bits == 32 ? 0xFFFFFFFFu : (uint32_t{1} << bits) - 1;
    ops.push_back({Op::kBypass, max, bits, 0});
    ops.push_back({Op::kBypass, 0, bits, 0});
    for (int n = 0; n < 20; ++n)
      ops.push_back({Op::kBypass, static_cast<uint32_t>(rng()) & max, bits, 0});
  }
  ExpectRoundTrip(ops, 1);
  // Bypass bits cost one bit each (to within the range split's rounding).
  std::vector<Op> many(2000, Op{Op::kBypass, 0x5A5A5A5Au, 32, 0});
  EXPECT_LT(EncodeOps(many, 1).size(), 2000 * 4 * 1.01);
}

TEST(RangeCoderTest, GolombAllOrdersIncludingMaximum) {
  std::vector<Op> ops;
  for (int k = 0; k <= kMaxGolombK; ++k) {
    for (uint32_t value :
         {0u, 1u, 2u, 3u, 255u, 256u, 65535u, 1u << 30, kMaxGolombValue - 1, kMaxGolombValue}) {
      ops.push_back({Op::kGolomb, value, k, 0});
    }
  }
  ExpectRoundTrip(ops, 1);
}

TEST(RangeCoderTest, GolombRejectsOverlongCodes) {
  // 40 zero bypass bits: a prefix no valid Exp-Golomb code has.
  for (int k : {0, 5, 30}) {
    RangeEncoder encoder;
    encoder.EncodeBypass(0, 32);
    encoder.EncodeBypass(0, 8);
    encoder.EncodeBypass(0xFFFFFFFFu, 32);
    const std::vector<uint8_t> bytes = encoder.Finish();
    RangeDecoder decoder(bytes.data(), bytes.size());
    decoder.DecodeGolomb(k);
    EXPECT_TRUE(decoder.HasError());
    EXPECT_EQ(decoder.Finish().code(), kErrCorrupt);
  }
  // Prefix within the limit but a value above kMaxGolombValue: k = 0, 31 zeros, then 32 ones.
  RangeEncoder encoder;
  encoder.EncodeBypass(0, 31);
  encoder.EncodeBypass(0xFFFFFFFFu, 32);
  const std::vector<uint8_t> bytes = encoder.Finish();
  RangeDecoder decoder(bytes.data(), bytes.size());
  decoder.DecodeGolomb(0);
  EXPECT_EQ(decoder.Finish().code(), kErrCorrupt);
}

TEST(RangeCoderTest, MixedSequences) {
  for (uint32_t seed = 1; seed <= 20; ++seed) ExpectRoundTrip(MixedOps(seed, 5000), 200);
}

TEST(RangeCoderTest, EveryTruncatedPrefixFailsOrDecodesSafely) {
  const std::vector<Op> ops = MixedOps(77, 3000);
  const std::vector<uint8_t> bytes = EncodeOps(ops, 200);
  size_t detected = 0;
  for (size_t size = 0; size < bytes.size(); ++size) {
    // A copy of exactly `size` bytes, so ASan catches any read past the prefix.
    const std::vector<uint8_t> prefix(bytes.begin(), bytes.begin() + static_cast<long>(size));
    Status finish;
    const size_t matching = DecodeOps(ops, 200, prefix.data(), prefix.size(), &finish);
    if (!finish.ok()) {
      ++detected;
    } else {
      EXPECT_LT(matching, ops.size());  // a prefix cannot carry the whole message
    }
  }
  // Losing even the last byte changes the decoded symbols and overruns the shorter stream.
  EXPECT_EQ(detected, bytes.size());
}

TEST(RangeCoderTest, RandomGarbageNeverCrashes) {
  std::mt19937 rng(2024);
  const std::vector<Op> ops = MixedOps(5, 400);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<uint8_t> garbage(rng() % 64);
    for (uint8_t& b : garbage) b = static_cast<uint8_t>(rng());
    Status finish;
    DecodeOps(ops, 200, garbage.data(), garbage.size(), &finish);
    // 400 ops need far more than 64 bytes: the decoder must notice it ran out.
    EXPECT_FALSE(finish.ok());
  }
}

TEST(RangeCoderTest, OverrunIsStickyAndBounded) {
  const uint8_t one_byte = 0xA5;
  RangeDecoder decoder(&one_byte, 1);
  for (int n = 0; n < 1000; ++n) decoder.DecodeBypass(32);
  EXPECT_TRUE(decoder.HasError());
  EXPECT_EQ(decoder.status().code(), kErrTruncated);
  EXPECT_EQ(decoder.Finish().code(), kErrTruncated);
}

// A literal transcription of the bit-serial decoding process of docs/spec/entropy_coding.md.
// RangeDecoder's 32-bit window must behave identically, valid stream or not.
class SpecDecoder {
 public:
  SpecDecoder(const uint8_t* data, size_t size) : data_(data), size_(size) {
    const int num_bits = static_cast<int>(std::min<uint64_t>(8 * size, 15));
    const uint32_t buf = ReadBits(num_bits);
    const uint32_t padded_buf = buf << (15 - num_bits);
    symbol_value_ = ((1u << 15) - 1) ^ padded_buf;
    symbol_range_ = 1u << 15;
    symbol_bits_left_ = 8 * static_cast<int64_t>(size) - 15;
  }
  int DecodeSymbol(uint16_t* cdf, int n) {
    uint32_t cur = symbol_range_;
    uint32_t prev;
    int symbol = -1;
    do {
      ++symbol;
      prev = cur;
      cur = (((symbol_range_ >> 8) * (cdf[symbol] >> 6)) >> 1) +
            4 * static_cast<uint32_t>(n - symbol - 1);
    } while (symbol_value_ < cur);
    symbol_range_ = prev - cur;
    symbol_value_ -= cur;
    Renormalize();
    // Adaptation as in the spec.
    const int rate =
        3 + (cdf[n] > 15) + (cdf[n] > 31) + std::min(FloorLog2(static_cast<uint32_t>(n)), 2);
    for (int i = 0; i < n - 1; ++i) {
      if (i < symbol)
        cdf[i] = static_cast<uint16_t>(cdf[i] + ((32768 - cdf[i]) >> rate));
      else
        cdf[i] = static_cast<uint16_t>(cdf[i] - (cdf[i] >> rate));
    }
    cdf[n] = static_cast<uint16_t>(cdf[n] + (cdf[n] < 32));
    return symbol;
  }
  int DecodeBypassBit() {
    uint16_t cdf[3] = {16384, 0, 0};
    const int bit = DecodeSymbolNoAdapt(cdf);
    return bit;
  }
  bool ExitOk() const { return symbol_bits_left_ >= -15; }

 private:
  static int FloorLog2(uint32_t x) { return 31 - __builtin_clz(x); }
  int DecodeSymbolNoAdapt(uint16_t* cdf) {
    uint16_t copy[3] = {cdf[0], cdf[1], cdf[2]};
    return DecodeSymbol(copy, 2);
  }
  uint32_t ReadBits(int n) {
    uint32_t x = 0;
    for (int i = 0; i < n; ++i, ++bit_pos_) {
      const uint32_t bit =
          bit_pos_ < 8 * size_ ? (data_[bit_pos_ >> 3] >> (7 - (bit_pos_ & 7))) & 1 : 0;
      x = (x << 1) | bit;
    }
    return x;
  }
  void Renormalize() {
    const int bits = 15 - FloorLog2(symbol_range_);
    symbol_range_ <<= bits;
    const uint32_t new_data = ReadBits(bits);
    symbol_value_ = ((symbol_value_ << bits) | ((1u << bits) - 1)) ^ new_data;
    symbol_bits_left_ -= bits;
  }

  const uint8_t* data_;
  size_t size_;
  uint64_t bit_pos_ = 0;
  uint32_t symbol_value_;
  uint32_t symbol_range_;
  int64_t symbol_bits_left_;
};

TEST(RangeCoderTest, WindowDecoderMatchesBitSerialSpecProcess) {
  std::mt19937 rng(31337);
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<uint8_t> bytes;
    if (trial % 2 == 0) {
      bytes = EncodeOps(MixedOps(static_cast<uint32_t>(trial), 200), 200);
      bytes.resize(bytes.size() - std::min<size_t>(bytes.size(), trial % 5));  // some truncated
    } else {
      bytes.resize(rng() % 48);
      for (uint8_t& b : bytes) b = static_cast<uint8_t>(rng());
    }
    RangeDecoder window(bytes.data(), bytes.size());
    SpecDecoder spec(bytes.data(), bytes.size());
    uint16_t cdf_a[11][17], cdf_b[11][17];
    for (int n = 2; n <= 16; n += 2) {
      InitUniformCdf(cdf_a[n / 2 - 1], n);
      InitUniformCdf(cdf_b[n / 2 - 1], n);
    }
    for (int step = 0; step < 600; ++step) {
      const uint32_t r = rng();
      if (r % 4 == 0) {
        ASSERT_EQ(window.DecodeBypassBit(), spec.DecodeBypassBit()) << trial << " " << step;
      } else {
        const int n = 2 * (1 + static_cast<int>((r >> 4) % 8));
        ASSERT_EQ(window.DecodeSymbol(cdf_a[n / 2 - 1], n), spec.DecodeSymbol(cdf_b[n / 2 - 1], n))
            << trial << " " << step;
      }
      // The window decoder flags overruns early; the spec only checks at exit. Both must agree
      // on every stream that is still acceptable.
      if (!window.HasError()) {
        ASSERT_EQ(window.Finish().ok(), spec.ExitOk()) << trial << " " << step;
      } else {
        ASSERT_FALSE(spec.ExitOk());
      }
    }
  }
}

}  // namespace
}  // namespace ecrf
