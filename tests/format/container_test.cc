#include "format/container.h"

#include <gtest/gtest.h>

#include <cstring>
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

TEST(Container, RandomBytesNeverCrash) {
  std::mt19937 rng(99);
  for (int t = 0; t < 2000; ++t) {
    std::vector<uint8_t> f(rng() % 64);
    for (auto& b : f) b = uint8_t(rng());
    if (f.size() >= 8 && (t % 2)) {
      std::memcpy(f.data(), "ECRF\x01\x00\x00\x00", 8);
    }
    (void)ReadAll(f);
  }
}

}  // namespace
}  // namespace ecrf
