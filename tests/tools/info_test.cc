// `ecrf info` prints what a stream says about itself; the meta chunk is untrusted text, so it
// comes out escaped and bounded whatever bytes it holds.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "conformance/costly_streams.h"
#include "format/container.h"
#include "tools/commands.h"

namespace ecrf {
namespace tools {
namespace {

std::vector<uint8_t> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

// A conformance stream with `meta` inserted before DONE.
std::vector<uint8_t> WithMetadata(const std::string& meta) {
  const std::vector<uint8_t> base =
      ReadBytes(std::string(ECRF_SOURCE_DIR) + "/tests/conformance/scene_16bit.ecrf");
  ContainerReader reader;
  EXPECT_TRUE(reader.Open(base.data(), base.size()).ok());
  ContainerWriter writer(reader.version_minor());
  for (bool done = false;;) {
    ChunkView chunk;
    EXPECT_TRUE(reader.Next(&chunk, &done).ok());
    if (done) break;
    writer.AddChunk(chunk.type, chunk.data, chunk.size);
  }
  writer.AddChunk(FourCC("meta"), reinterpret_cast<const uint8_t*>(meta.data()), meta.size());
  return writer.Finish();
}

std::string InfoOutput(const std::vector<uint8_t>& stream) {
  const std::string path = std::string(::testing::TempDir()) + "/info_meta.ecrf";
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(stream.data()), stream.size());
  std::string arg0 = "info", arg1 = path;
  char* argv[] = {arg0.data(), arg1.data()};
  ::testing::internal::CaptureStdout();
  const int rc = RunInfo(2, argv);
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(rc, 0);
  std::remove(path.c_str());
  return out;
}

TEST(Info, MetadataIsEscapedAndTruncated) {
  const std::string hostile =
      "{\"a\":\"\x1b]0;owned\x07\x1b[2J\xc2\x9b"
      "31m\"}" +
      std::string(1 << 20, 'x');
  const std::string out = InfoOutput(WithMetadata(hostile));
  EXPECT_EQ(out.find('\x1b'), std::string::npos) << "an escape sequence reached the terminal";
  EXPECT_EQ(out.find('\x07'), std::string::npos);
  EXPECT_EQ(out.find("\xc2\x9b"), std::string::npos);
  EXPECT_NE(out.find("\\x1b]0;owned\\x07"), std::string::npos) << out.substr(0, 2000);
  EXPECT_NE(out.find("more bytes)"), std::string::npos);
  EXPECT_LT(out.size(), size_t(8192));
  // Plain ASCII JSON is shown as it is.
  EXPECT_NE(InfoOutput(WithMetadata("{\"encoder\":\"ecrf\"}")).find("{\"encoder\":\"ecrf\"}"),
            std::string::npos);
}

// `info --md5` hashes every decoded value: a small stream of large untouched (all-zero) grids
// decodes cheaply, and its checksums are charged to the same budget, before any hashing.
TEST(Info, ChecksumsOfLargeUntouchedGridsAreChargedToTheDecodeBudget) {
  costly::CostlyScene cs;
  cs.res = 512;
  cs.density_rank = 16;
  cs.appearance_rank = 16;  // 2 x (3 x 512^2 x 16 + 3 x 512 x 16) = 25.2 M values
  const std::vector<uint8_t> stream = costly::BuildCostlyStream(cs);
  ASSERT_LT(stream.size(), size_t{8192});
  const std::string path = std::string(::testing::TempDir()) + "/info_md5.ecrf";
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(stream.data()), stream.size());
  auto run = [&](std::vector<std::string> args) {
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    ::testing::internal::CaptureStdout();
    std::string error;
    try {
      RunInfo(int(argv.size()), argv.data());
    } catch (const std::exception& e) {
      error = e.what();
    }
    ::testing::internal::GetCapturedStdout();
    return error;
  };
  // It decodes within its budget, and the checksums would pass it: refused, naming the flag.
  EXPECT_EQ(run({"info", path}), "");
  const std::string refused = run({"info", path, "--md5"});
  EXPECT_NE(refused.find("--md5 of its 25214976 decoded values"), std::string::npos) << refused;
  // With no limit the checksums are computed.
  EXPECT_EQ(run({"info", path, "--md5", "--decode-budget", "0"}), "");
  std::remove(path.c_str());
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
