// `ecrf conformance --write DIR | --check DIR`: rebuilds the conformance vectors of
// tests/conformance (streams and the manifest of output MD5s), or checks that the checked-in
// ones still decode to their MD5s and are what this encoder writes (if not, the format changed).
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/common/coef_vectors.h"
#include "tools/commands.h"
#include "trainer/checkpoint.h"

namespace ecrf {
namespace tools {

int RunConformance(int argc, char** argv) {
  if (argc != 3 || (std::strcmp(argv[1], "--write") && std::strcmp(argv[1], "--check"))) {
    std::fprintf(stderr, "usage: ecrf conformance --write DIR | --check DIR\n");
    return 2;
  }
  const bool write = !std::strcmp(argv[1], "--write");
  const std::string dir = argv[2];
  std::ostringstream manifest;
  int failures = 0;
  for (const auto& v : conformance::CoefVectors()) {
    const std::vector<uint8_t> stream = conformance::EncodeVector(v);
    const std::string md5 = conformance::DecodeVectorMd5(v, stream);
    const std::string path = dir + "/" + v.name + ".bin";
    manifest << v.name << ".bin " << md5 << "\n";
    if (write) {
      trainer::WriteFileAtomically(path, stream.data(), stream.size());
      std::printf("wrote %s (%zu bytes, output md5 %s)\n", path.c_str(), stream.size(), md5.c_str());
      continue;
    }
    const std::vector<uint8_t> stored = trainer::ReadWholeFile(path);
    const std::string stored_md5 = conformance::DecodeVectorMd5(v, stored);
    const bool same_bytes = stored == stream;
    std::printf("%-36s decode %s, encoder output %s\n", v.name,
                stored_md5 == md5 ? "matches" : "DIFFERS", same_bytes ? "identical" : "CHANGED (format changed?)");
    failures += stored_md5 != md5 || !same_bytes;
  }
  if (write) {
    const std::string text = manifest.str();
    trainer::WriteFileAtomically(dir + "/coefficients.md5", text.data(), text.size());
    std::printf("wrote %s/coefficients.md5\n", dir.c_str());
  }
  return failures ? 1 : 0;
}

}  // namespace tools
}  // namespace ecrf
