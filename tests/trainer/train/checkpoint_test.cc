#include "trainer/train/checkpoint.h"

#include <gtest/gtest.h>
#include <zstd.h>

#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "trainer/data/file_io.h"

namespace ecrf {
namespace trainer {
namespace {

std::string TempPath(const char* name) { return std::string(::testing::TempDir()) + "/" + name; }

TEST(Checkpoint, RoundTrip) {
  Checkpoint ck;
  ck.json = R"({"iteration": 12})";
  ck.arrays.push_back({"density.plane0", {2, 3}, {1, 2, 3, 4, 5, 6}});
  ck.arrays.push_back({"empty", {0}, {}});
  const std::string path = TempPath("ck_roundtrip.ckpt");
  WriteCheckpoint(path, ck);
  const Checkpoint back = ReadCheckpoint(path);
  EXPECT_EQ(back.json, ck.json);
  ASSERT_EQ(back.arrays.size(), 2u);
  EXPECT_EQ(back.arrays[0].shape, (std::vector<int64_t>{2, 3}));
  EXPECT_EQ(back.arrays[0].data, ck.arrays[0].data);
  ASSERT_NE(back.Find("empty"), nullptr);
  EXPECT_EQ(back.Find("missing"), nullptr);
}

TEST(Checkpoint, DamagedFilesGiveErrorsNamingThePath) {
  Checkpoint ck;
  ck.arrays.push_back({"a", {100}, std::vector<float>(100, 1.5f)});
  const std::string path = TempPath("ck_damaged.ckpt");
  WriteCheckpoint(path, ck);
  auto bytes = ReadWholeFile(path);
  for (size_t cut : {size_t(0), size_t(10), bytes.size() / 2, bytes.size() - 1}) {
    WriteFileAtomically(path, bytes.data(), cut);
    try {
      ReadCheckpoint(path);
      FAIL() << "accepted a checkpoint cut at " << cut;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(ReadCheckpoint(TempPath("does_not_exist.ckpt")), std::runtime_error);
}

// A small file whose zstd frame expands to a gigabyte (zeros compress 30000:1) is refused from
// its sizes, before anything is decompressed; weights never compress like that.
TEST(Checkpoint, DecompressionBombsAreRefusedFromTheirSizes) {
  const uint64_t raw_size = uint64_t(1) << 30;
  std::vector<uint8_t> file = {'E', 'C', 'R', 'F', 'C', 'K', 'P', '2'};
  for (int b = 0; b < 8; ++b) file.push_back(uint8_t(raw_size >> (8 * b)));
  ZSTD_CCtx* cctx = ZSTD_createCCtx();
  ASSERT_NE(cctx, nullptr);
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 1);
  ZSTD_CCtx_setPledgedSrcSize(cctx, raw_size);
  const std::vector<uint8_t> zeros(size_t(1) << 20, 0);
  std::vector<uint8_t> out(ZSTD_CStreamOutSize());
  for (uint64_t done = 0; done < raw_size; done += zeros.size()) {
    const bool last = done + zeros.size() == raw_size;
    ZSTD_inBuffer in{zeros.data(), zeros.size(), 0};
    size_t left;
    do {
      ZSTD_outBuffer o{out.data(), out.size(), 0};
      left = ZSTD_compressStream2(cctx, &o, &in, last ? ZSTD_e_end : ZSTD_e_continue);
      ASSERT_FALSE(ZSTD_isError(left));
      file.insert(file.end(), out.begin(), out.begin() + o.pos);
    } while (last ? left != 0 : in.pos < in.size);
  }
  ZSTD_freeCCtx(cctx);
  ASSERT_LT(file.size(), size_t(1) << 20);
  const std::string path = TempPath("ck_bomb.ckpt");
  WriteFileAtomically(path, file);
  try {
    ReadCheckpoint(path);
    FAIL() << "accepted a decompression bomb";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("claims 1073741824 bytes, more than 1000 times its size"),
              std::string::npos)
        << e.what();
  }
}

// Bytes after the frame are named as such (it used to say "holds N bytes, its header says N").
TEST(Checkpoint, BytesAfterTheFrameAreNamed) {
  Checkpoint ck;
  ck.arrays.push_back({"a", {100}, std::vector<float>(100, 1.5f)});
  const std::string path = TempPath("ck_appended.ckpt");
  WriteCheckpoint(path, ck);
  std::vector<uint8_t> bytes = ReadWholeFile(path);
  bytes.insert(bytes.end(), {1, 2, 3, 4, 5});
  WriteFileAtomically(path, bytes);
  try {
    ReadCheckpoint(path);
    FAIL() << "accepted a checkpoint with bytes appended";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(
        std::string(e.what()).find(path + ": checkpoint is damaged: 5 bytes follow its zstd frame"),
        std::string::npos)
        << e.what();
  }
}

// zstd's content checksum turns every flipped byte into an error or, where the flip hits a bit
// the decompressor never reads, into the very same content: never altered weights. A damaged
// size field is refused before it is allocated.
TEST(Checkpoint, EveryFlippedByteAndHugeSizeFieldIsRefused) {
  Checkpoint ck;
  ck.json = R"({"iteration": 7})";
  std::vector<float> values(3000);
  for (size_t i = 0; i < values.size(); ++i) values[i] = float(i % 97) * 0.25f;
  ck.arrays.push_back({"grid", {3, 1000}, values});
  const std::string path = TempPath("ck_flip.ckpt");
  WriteCheckpoint(path, ck);
  const std::vector<uint8_t> good = ReadWholeFile(path);
  for (size_t at = 0; at < good.size(); ++at) {
    for (uint8_t bit : {uint8_t(0x01), uint8_t(0x80)}) {
      std::vector<uint8_t> bad = good;
      bad[at] ^= bit;
      WriteFileAtomically(path, bad.data(), bad.size());
      try {
        const Checkpoint back = ReadCheckpoint(path);
        EXPECT_TRUE(back.json == ck.json && back.arrays.size() == 1 &&
                    back.arrays[0].data == values)
            << "byte " << at << " of " << good.size() << " flipped (bit " << int(bit)
            << ") read as other content";
      } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      }
    }
  }
  std::vector<uint8_t> huge = good;
  const uint64_t size = uint64_t(1) << 42;
  std::memcpy(huge.data() + 8, &size, 8);
  WriteFileAtomically(path, huge.data(), huge.size());
  EXPECT_THROW(ReadCheckpoint(path), std::runtime_error);
}

// Checkpoints written before the checksum (magic ECRFCKP1) still load.
TEST(Checkpoint, ReadsVersionOneFilesWithoutChecksum) {
  Checkpoint ck;
  ck.json = R"({"iteration": 3})";
  ck.arrays.push_back({"a", {2}, {0.5f, -2.0f}});
  const std::string path = TempPath("ck_v2.ckpt");
  WriteCheckpoint(path, ck);
  const std::vector<uint8_t> v2 = ReadWholeFile(path);
  uint64_t raw_size;
  std::memcpy(&raw_size, v2.data() + 8, 8);
  std::vector<uint8_t> raw(raw_size);
  ASSERT_EQ(ZSTD_decompress(raw.data(), raw.size(), v2.data() + 16, v2.size() - 16), raw_size);
  std::vector<uint8_t> v1(16 + ZSTD_compressBound(raw.size()));
  std::memcpy(v1.data(), "ECRFCKP1", 8);
  std::memcpy(v1.data() + 8, &raw_size, 8);
  const size_t z =
      ZSTD_compress(v1.data() + 16, v1.size() - 16, raw.data(), raw.size(), 3);  // no checksum
  ASSERT_FALSE(ZSTD_isError(z));
  v1.resize(16 + z);
  WriteFileAtomically(path, v1.data(), v1.size());
  const Checkpoint back = ReadCheckpoint(path);
  EXPECT_EQ(back.json, ck.json);
  ASSERT_EQ(back.arrays.size(), 1u);
  EXPECT_EQ(back.arrays[0].data, ck.arrays[0].data);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
