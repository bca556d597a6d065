// Whole-file reads and the one way ecrf writes a file: to a unique temporary sibling, flushed to
// disk, then renamed over the target, so that a reader never sees a half-written file and an
// interrupted write leaves the old file (or none) in place.
#ifndef ECRF_TRAINER_DATA_FILE_IO_H_
#define ECRF_TRAINER_DATA_FILE_IO_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ecrf {
namespace trainer {

// Atomically replaces `path` with `bytes`. Throws std::runtime_error naming the path and the
// problem; on failure the temporary file is removed and `path` is untouched.
void WriteFileAtomically(const std::string& path, const void* bytes, size_t size);
inline void WriteFileAtomically(const std::string& path, const std::vector<uint8_t>& bytes) {
  WriteFileAtomically(path, bytes.data(), bytes.size());
}
inline void WriteFileAtomically(const std::string& path, const std::string& text) {
  WriteFileAtomically(path, text.data(), text.size());
}

// Throws std::runtime_error naming the path and the problem.
std::vector<uint8_t> ReadWholeFile(const std::string& path);

// Throws std::runtime_error naming the path and what it is unless it is a regular file (or a
// link to one): opening a FIFO for reading blocks until something writes to it, and a device
// may never end (#60). Every input file of the trainer goes through it.
void CheckRegularFile(const std::string& path);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_DATA_FILE_IO_H_
