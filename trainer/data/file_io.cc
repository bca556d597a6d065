#include "trainer/data/file_io.h"

#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace ecrf {
namespace trainer {

void WriteFileAtomically(const std::string& path, const void* bytes, size_t size) {
  // A unique sibling name keeps concurrent writers (threads or processes) from sharing a temp
  // file, and rename() within one directory is atomic.
  static std::atomic<unsigned> counter{0};
  const std::string tmp =
      path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter.fetch_add(1));
  FILE* f = std::fopen(tmp.c_str(), "wbx");
  if (!f)
    throw std::runtime_error(path + ": cannot create temporary file " + tmp + ": " +
                             std::strerror(errno));
  const bool written = size == 0 || std::fwrite(bytes, 1, size, f) == size;
  const bool flushed = written && std::fflush(f) == 0 && ::fsync(::fileno(f)) == 0;
  int saved_errno = errno;
  const bool closed = std::fclose(f) == 0;
  if (flushed && !closed) saved_errno = errno;
  if (!written || !flushed || !closed) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": write error: " + std::strerror(saved_errno));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    saved_errno = errno;
    std::remove(tmp.c_str());
    throw std::runtime_error(
        path + ": cannot rename the temporary file into place: " + std::strerror(saved_errno));
  }
}

void CheckRegularFile(const std::string& path) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0)
    throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  if (S_ISREG(st.st_mode)) return;
  const char* what = S_ISDIR(st.st_mode)                          ? "a directory"
                     : S_ISFIFO(st.st_mode)                       ? "a FIFO (named pipe)"
                     : S_ISSOCK(st.st_mode)                       ? "a socket"
                     : S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "a device"
                                                                  : "a special file";
  throw std::runtime_error(path + ": is " + std::string(what) + ", not a file to read");
}

std::vector<uint8_t> ReadWholeFile(const std::string& path) {
  CheckRegularFile(path);
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  std::vector<uint8_t> bytes;
  uint8_t buffer[1 << 16];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), f)) > 0)
    bytes.insert(bytes.end(), buffer, buffer + n);
  const bool failed = std::ferror(f);
  std::fclose(f);
  if (failed) throw std::runtime_error(path + ": read error");
  return bytes;
}

}  // namespace trainer
}  // namespace ecrf
