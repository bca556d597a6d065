#include "format/container.h"

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <random>
#include <string>

#include "format/crc32.h"

namespace ecrf {
namespace {

TEST(Crc32, KnownValues) {
  const char* s = "123456789";
  EXPECT_EQ(Crc32(reinterpret_cast<const uint8_t*>(s), 9), 0xCBF43926u);
  EXPECT_EQ(Crc32(nullptr, 0), 0u);
  // Incremental == one shot, across the slice-by-4 boundary.
  std::vector<uint8_t> data(1001);
  for (size_t i = 0; i < data.size(); ++i) data[i] = uint8_t(i * 131 + 7);
  const uint32_t whole = Crc32(data.data(), data.size());
  for (size_t split : {0, 1, 3, 4, 5, 500, 1001}) {
    uint32_t c = Crc32Update(0, data.data(), split);
    c = Crc32Update(c, data.data() + split, data.size() - split);
    EXPECT_EQ(c, whole) << split;
  }
}

std::vector<uint8_t> SampleFile() {
  ContainerWriter w;
  const std::string a = "hello", b(1000, 'x');
  w.AddChunk(FourCC("HEAD"), reinterpret_cast<const uint8_t*>(a.data()), a.size());
  w.AddChunk(FourCC("meta"), reinterpret_cast<const uint8_t*>(b.data()), b.size());
  w.AddChunk(FourCC("EMPT"), nullptr, 0);
  return w.Finish();
}

TEST(Container, RoundTrip) {
  const auto file = SampleFile();
  EXPECT_EQ(file.size(), kFileHeaderBytes + 4 * kChunkOverheadBytes + 5 + 1000);
  ContainerReader r;
  ASSERT_TRUE(r.Open(file.data(), file.size()).ok());
  EXPECT_EQ(r.version_major(), kVersionMajor);
  ChunkView c;
  bool done;
  ASSERT_TRUE(r.Next(&c, &done).ok());
  EXPECT_EQ(c.type, FourCC("HEAD"));
  EXPECT_TRUE(IsCriticalChunk(c.type));
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(c.data), c.size), "hello");
  ASSERT_TRUE(r.Next(&c, &done).ok());
  EXPECT_FALSE(IsCriticalChunk(c.type));
  EXPECT_EQ(c.size, 1000u);
  ASSERT_TRUE(r.Next(&c, &done).ok());
  EXPECT_EQ(c.size, 0u);
  EXPECT_FALSE(done);
  ASSERT_TRUE(r.Next(&c, &done).ok());
  EXPECT_TRUE(done);
  EXPECT_EQ(c.type, kChunkDone);
}

Status ReadAll(const std::vector<uint8_t>& f) {
  ContainerReader r;
  ECRF_RETURN_IF_ERROR(r.Open(f.data(), f.size()));
  for (;;) {
    ChunkView c;
    bool done;
    ECRF_RETURN_IF_ERROR(r.Next(&c, &done));
    if (done) return Status::Ok();
  }
}

TEST(Container, EveryTruncationIsAnError) {
  const auto file = SampleFile();
  for (size_t n = 0; n < file.size(); ++n) {
    std::vector<uint8_t> prefix(file.begin(), file.begin() + n);
    const Status s = ReadAll(prefix);
    ASSERT_FALSE(s.ok()) << "prefix " << n;
    EXPECT_TRUE(s.code() == kErrTruncated || s.code() == kErrCorrupt) << n << ": " << s.message();
  }
}

TEST(Container, EveryBitFlipIsDetected) {
  const auto file = SampleFile();
  for (size_t i = 0; i < file.size(); ++i) {
    if (i == 5) continue;  // the minor version: any value is legal (backward-compatible additions)
    for (int bit = 0; bit < 8; bit += 3) {
      auto f = file;
      f[i] ^= uint8_t(1 << bit);
      ASSERT_FALSE(ReadAll(f).ok()) << "byte " << i << " bit " << bit;
    }
  }
}

TEST(Container, MessagesSayWhatAndWhere) {
  auto f = SampleFile();
  f[kFileHeaderBytes + 8] ^= 1;  // first payload byte
  const Status s = ReadAll(f);
  EXPECT_EQ(s.code(), kErrChecksum);
  EXPECT_NE(std::string(s.message()).find("HEAD"), std::string::npos) << s.message();
  EXPECT_NE(std::string(s.message()).find("offset 8"), std::string::npos) << s.message();

  std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', 0, 0, 0, 0};
  EXPECT_EQ(ReadAll(png).code(), kErrCorrupt);
  auto v2 = SampleFile();
  v2[4] = 2;
  EXPECT_EQ(ReadAll(v2).code(), kErrUnsupported);
  auto trailing = SampleFile();
  trailing.push_back(0);
  EXPECT_EQ(ReadAll(trailing).code(), kErrCorrupt);
}

TEST(Container, HugeLengthIsRejectedBeforeUse) {
  auto f = SampleFile();
  const uint32_t huge = 0xFFFFFFF0u;
  std::memcpy(&f[kFileHeaderBytes + 4], &huge, 4);
  EXPECT_EQ(ReadAll(f).code(), kErrLimit);
  const uint32_t big = 1u << 20;  // legal size but past the end of the buffer
  std::memcpy(&f[kFileHeaderBytes + 4], &big, 4);
  EXPECT_EQ(ReadAll(f).code(), kErrTruncated);
}

// What a reader must make of `f` by SPEC.md 2.1-2.2, written from the specification and not
// from ContainerReader: the chunks up to DONE, or the category of the first check that fails.
struct SpecifiedParse {
  int code = kOk;
  std::vector<ChunkView> chunks;
};

SpecifiedParse ParseAsSpecified(const std::vector<uint8_t>& f) {
  SpecifiedParse p;
  const auto fail = [&p](int code) {
    p.code = code;
    return p;
  };
  const auto u32 = [&f](size_t at) {
    return uint32_t(f[at]) | uint32_t(f[at + 1]) << 8 | uint32_t(f[at + 2]) << 16 |
           uint32_t(f[at + 3]) << 24;
  };
  const auto type_char = [](uint8_t c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == ' ';
  };
  if (f.size() < 4) return fail(kErrTruncated);
  if (std::memcmp(f.data(), "ECRF", 4) != 0) return fail(kErrCorrupt);
  if (f.size() < 8) return fail(kErrTruncated);
  if (f[4] != 1) return fail(kErrUnsupported);
  if (f[6] != 0 || f[7] != 0) return fail(kErrCorrupt);
  for (size_t pos = 8;;) {
    if (f.size() - pos < 8) return fail(kErrTruncated);
    const uint32_t type = u32(pos), length = u32(pos + 4);
    for (int i = 0; i < 4; ++i) {
      if (!type_char(uint8_t(type >> (8 * i)))) return fail(kErrCorrupt);
    }
    if (length > (1u << 28)) return fail(kErrLimit);
    if (f.size() - pos - 8 < size_t(length) + 4) return fail(kErrTruncated);
    if (Crc32(&f[pos], 8 + size_t(length)) != u32(pos + 8 + length)) return fail(kErrChecksum);
    p.chunks.push_back({type, f.data() + pos + 8, length, pos});
    pos += 12 + size_t(length);
    if (type == FourCC("DONE")) return length == 0 && pos == f.size() ? p : fail(kErrCorrupt);
  }
}

// A stream that reaches every check: valid chunks of random types and sizes, then at most one
// damage (truncation, a flipped byte, a random length or version, bytes after DONE).
std::vector<uint8_t> RandomStream(std::mt19937& rng) {
  static const char kTypeChars[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789 ";
  ContainerWriter w{static_cast<uint8_t>(rng())};
  for (int chunks = int(rng() % 4); chunks > 0; --chunks) {
    char type[5] = {0};
    for (int i = 0; i < 4; ++i) type[i] = kTypeChars[rng() % (sizeof(kTypeChars) - 1)];
    std::vector<uint8_t> payload(rng() % 40);
    for (auto& b : payload) b = uint8_t(rng());
    w.AddChunk(FourCC(type), payload);
  }
  std::vector<uint8_t> f = w.Finish();
  const size_t at = rng() % f.size();
  switch (rng() % 6) {
    case 0:
      f.resize(at);
      break;
    case 1:
      f[at] ^= uint8_t(1 + rng() % 255);
      break;
    case 2: {  // a chunk length field, when `at` falls on a chunk header: any u32, often > 2^28
      const uint32_t length = rng();
      if (at + 8 <= f.size()) std::memcpy(&f[at + 4], &length, 4);
      break;
    }
    case 3:
      f[4] = uint8_t(rng() % 3);
      break;
    case 4:
      f.push_back(uint8_t(rng()));
      break;
    default:
      break;
  }
  return f;
}

// Every byte string gets the verdict SPEC.md 2 gives it: the same chunks (each inside the input)
// or the same error category, with a message. Built with ECRF_SANITIZE the exactly-sized inputs
// also prove the reader never reads past the end.
TEST(Container, RandomBytesGetTheSpecifiedVerdict) {
  std::mt19937 rng(99);
  std::map<int, int> verdicts;
  for (int t = 0; t < 6000; ++t) {
    std::vector<uint8_t> f;
    if (t % 3 == 0) {  // noise, half of it behind a valid file header
      f.resize(rng() % 64);
      for (auto& b : f) b = uint8_t(rng());
      if (f.size() >= 8 && t % 2) std::memcpy(f.data(), "ECRF\x01\x00\x00\x00", 8);
    } else {
      f = RandomStream(rng);
    }
    const SpecifiedParse expected = ParseAsSpecified(f);
    ContainerReader r;
    std::vector<ChunkView> chunks;
    Status s = r.Open(f.data(), f.size());
    for (bool done = false; s.ok() && !done;) {
      ChunkView c;
      s = r.Next(&c, &done);
      if (s.ok()) chunks.push_back(c);
    }
    ++verdicts[s.code()];
    ASSERT_EQ(s.code(), expected.code)
        << "input " << t << " (" << f.size() << " bytes): " << s.message();
    if (!s.ok()) {
      EXPECT_NE(s.message()[0], '\0') << "input " << t;
      continue;
    }
    ASSERT_EQ(chunks.size(), expected.chunks.size()) << "input " << t;
    for (size_t i = 0; i < chunks.size(); ++i) {
      EXPECT_EQ(chunks[i].type, expected.chunks[i].type) << "input " << t << " chunk " << i;
      EXPECT_EQ(chunks[i].offset, expected.chunks[i].offset) << "input " << t << " chunk " << i;
      EXPECT_EQ(chunks[i].size, expected.chunks[i].size) << "input " << t << " chunk " << i;
      EXPECT_EQ(chunks[i].data, expected.chunks[i].data) << "input " << t << " chunk " << i;
      EXPECT_LE(chunks[i].data + chunks[i].size, f.data() + f.size()) << "input " << t;
    }
  }
  // The inputs reach every verdict but the chunk-count limit (65,536 chunks), often enough that
  // a reader which confused two of them would be caught.
  for (int code : {kOk, kErrTruncated, kErrCorrupt, kErrUnsupported, kErrLimit, kErrChecksum}) {
    EXPECT_GE(verdicts[code], 50) << ErrorCodeName(code);
  }
  EXPECT_EQ(verdicts.size(), 6u);
}

}  // namespace
}  // namespace ecrf
