// A directory of its own for one test, under the system's temporary directory, removed with
// everything in it when the ScopedTempDir goes out of scope, also when an assertion ends the test
// early (tests used to pair mkdtemp with a cleanup of their own, and some left theirs behind).
#ifndef ECRF_TESTS_COMMON_SCOPED_TEMP_DIR_H_
#define ECRF_TESTS_COMMON_SCOPED_TEMP_DIR_H_

#include <stdlib.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace ecrf {
namespace testing_util {

class ScopedTempDir {
 public:
  // prefix names the test in the directory's name: TMPDIR/prefix_XXXXXX.
  explicit ScopedTempDir(const std::string& prefix = "ecrf_test") {
    const std::string pattern =
        (std::filesystem::temp_directory_path() / (prefix + "_XXXXXX")).string();
    std::vector<char> name(pattern.begin(), pattern.end());
    name.push_back('\0');
    if (mkdtemp(name.data()) == nullptr)
      throw std::runtime_error("cannot create a temporary directory " + pattern);
    path_ = name.data();
  }
  ~ScopedTempDir() {
    std::error_code error;
    std::filesystem::remove_all(path_, error);
  }
  ScopedTempDir(const ScopedTempDir&) = delete;
  ScopedTempDir& operator=(const ScopedTempDir&) = delete;

  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace testing_util
}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_SCOPED_TEMP_DIR_H_
