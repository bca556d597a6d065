#include "trainer/checkpoint.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <stdexcept>
#include <string>

namespace ecrf {
namespace trainer {
namespace {

std::string TempPath(const char* name) {
  return std::string(::testing::TempDir()) + "/" + name;
}

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

}  // namespace
}  // namespace trainer
}  // namespace ecrf
