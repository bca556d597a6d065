#include "tools/cli_args.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace ecrf {
namespace tools {

float ParseFloat(const char* flag, const char* value) {
  char* end = nullptr;
  errno = 0;
  const float v = std::strtof(value, &end);
  if (errno || !end || *end || !(v >= 0.0f)) {
    throw std::invalid_argument(std::string(flag) + ": '" + value +
                                "' is not a non-negative number");
  }
  return v;
}

// "16x16x16" or "8x8" into n values, each a power of two <= 32.
void ParseShape(const char* flag, const std::string& text, int n, int* out) {
  size_t pos = 0;
  for (int i = 0; i < n; ++i) {
    const size_t x = text.find('x', pos);
    const std::string part = text.substr(pos, x == std::string::npos ? std::string::npos : x - pos);
    const int v = std::atoi(part.c_str());
    if (part.empty() || v < 1 || v > 32 || (v & (v - 1)) ||
        (i + 1 < n) == (x == std::string::npos)) {
      throw std::invalid_argument(std::string(flag) + ": '" + text + "' is not " +
                                  std::to_string(n) + " powers of two <= 32 joined by 'x'");
    }
    out[i] = v;
    pos = x == std::string::npos ? text.size() : x + 1;
  }
}

int ParseInt(const char* flag, const char* value) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(value, &end, 10);
  if (errno || !end || *end || v < 0 || v > 1000000000) {
    throw std::invalid_argument(std::string(flag) + ": '" + value +
                                "' is not a non-negative integer");
  }
  return int(v);
}

bool IsDirectory(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

bool FileExists(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0;
}

void MakeDirectory(const std::string& dir, std::vector<std::string>* created) {
  // Parents first, as `mkdir -p` does: "-o run/x" in an empty directory must work.
  for (size_t slash = dir.find('/', 1); slash != std::string::npos;
       slash = dir.find('/', slash + 1)) {
    const std::string parent = dir.substr(0, slash);
    if (mkdir(parent.c_str(), 0755) == 0) {
      if (created) created->push_back(parent);
    } else if (errno != EEXIST) {
      throw std::runtime_error(dir + ": cannot create directory " + parent + ": " +
                               std::strerror(errno));
    }
  }
  if (mkdir(dir.c_str(), 0755) == 0) {
    if (created) created->push_back(dir);
  } else if (errno != EEXIST) {
    throw std::runtime_error(dir + ": cannot create directory: " + std::strerror(errno));
  }
  if (!IsDirectory(dir)) throw std::runtime_error(dir + ": exists and is not a directory");
}

OutputDirectory::OutputDirectory(const std::string& dir) {
  MakeDirectory(dir, &created_);
  const std::string probe = dir + "/.ecrf_write_probe";
  errno = 0;
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  bool ok = f && std::fputc('\n', f) != EOF;
  if (f) ok = std::fclose(f) == 0 && ok;
  const int error = errno;
  std::remove(probe.c_str());
  if (!ok) {
    for (auto it = created_.rbegin(); it != created_.rend(); ++it) rmdir(it->c_str());
    throw std::runtime_error(
        dir + ": cannot write into this directory: " + std::strerror(error ? error : EIO));
  }
}

OutputDirectory::~OutputDirectory() {
  // rmdir removes empty directories only: whatever the job wrote stays, and so do its parents.
  for (auto it = created_.rbegin(); it != created_.rend(); ++it) rmdir(it->c_str());
}

const char* FlagValue(int argc, char** argv, int* i) {
  if (*i + 1 >= argc) throw std::invalid_argument(std::string(argv[*i]) + " needs a value");
  return argv[++*i];
}

}  // namespace tools
}  // namespace ecrf
