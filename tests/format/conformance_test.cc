// The checked-in conformance vectors decode to their listed MD5s, and this encoder still writes
// exactly those streams: if either fails, the bitstream changed (see tests/conformance/README.md).
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>

#include "conformance/coef_vectors.h"

namespace ecrf {
namespace {

const std::string kDir = std::string(ECRF_SOURCE_DIR) + "/tests/conformance/";

std::vector<uint8_t> ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)),
                              std::istreambuf_iterator<char>());
}

std::map<std::string, std::string> Manifest() {
  std::map<std::string, std::string> m;
  std::ifstream in(kDir + "coefficients.md5");
  std::string file, md5;
  while (in >> file >> md5) m[file] = md5;
  return m;
}

TEST(Conformance, Md5ImplementationMatchesRfc1321) {
  EXPECT_EQ(conformance::Md5Hex("", 0), "d41d8cd98f00b204e9800998ecf8427e");
  EXPECT_EQ(conformance::Md5Hex("abc", 3), "900150983cd24fb0d6963f7d28e17f72");
  const std::string s =
      "12345678901234567890123456789012345678901234567890123456789012345678901234567890";
  EXPECT_EQ(conformance::Md5Hex(s.data(), s.size()), "57edf4a22be3c955ac49da2e2107b67a");
}

TEST(Conformance, CheckedInVectorsDecodeToTheirMd5) {
  const auto manifest = Manifest();
  ASSERT_EQ(manifest.size(), conformance::CoefVectors().size())
      << "missing " << kDir << "coefficients.md5";
  for (const auto& v : conformance::CoefVectors()) {
    const std::string file = std::string(v.name) + ".bin";
    const std::vector<uint8_t> stream = ReadFile(kDir + file);
    ASSERT_FALSE(stream.empty()) << file;
    ASSERT_TRUE(manifest.count(file)) << file;
    EXPECT_EQ(conformance::DecodeVectorMd5(v, stream), manifest.at(file)) << file;
    // One flipped bit anywhere changes the output or fails the decode.
    std::vector<uint8_t> damaged = stream;
    damaged[damaged.size() / 2] ^= 0x10;
    EXPECT_NE(conformance::DecodeVectorMd5(v, damaged), manifest.at(file)) << file;
  }
}

TEST(Conformance, EncoderStillWritesTheCheckedInStreams) {
  for (const auto& v : conformance::CoefVectors()) {
    const std::vector<uint8_t> stream = ReadFile(kDir + v.name + ".bin");
    EXPECT_TRUE(conformance::EncodeVector(v) == stream)
        << v.name
        << ": the encoder's output changed. If intended, the bitstream version must change "
        << "and the vectors be rebuilt with `ecrf conformance --write tests/conformance`.";
  }
}

}  // namespace
}  // namespace ecrf
