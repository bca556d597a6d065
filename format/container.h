// The .ecrf container: a signature and version, then typed chunks, each with its length and a
// CRC-32, ending with a DONE chunk. Little endian throughout (SPEC.md section "Container").
//
// Chunk types are four ASCII characters. As in PNG, an upper-case first letter marks a critical
// chunk (a decoder that does not know it must stop) and a lower-case one an ancillary chunk
// (safe to skip), so old decoders can read streams that carry new optional data.
#ifndef ECRF_FORMAT_CONTAINER_H_
#define ECRF_FORMAT_CONTAINER_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "format/status.h"

namespace ecrf {

constexpr uint8_t kSignature[4] = {'E', 'C', 'R', 'F'};
constexpr uint8_t kVersionMajor = 1;
// The newest minor version this implementation knows. A stream carries the lowest minor version
// whose features it uses (1.1: MLPW precision 2, the quantized MLP; 1.2: the unbounded scene
// model; 1.3: the forward-facing scene model and its NDCP chunk; 1.4: the wide base-level contexts
// of the coefficient coder, in any COEF chunk whose wide code is the shorter; 1.5: the neighbour
// contexts likewise; 1.6: the deferred appearance head; 1.7: spherical-harmonics colour, HEAD
// hidden 0; 1.8: the MLP with one hidden layer, MLPW layers 1; 1.9: HEAD density_activation, ReLU
// density; unless
// EncodeOptions::max_version_minor asks for a stream older decoders read).
constexpr uint8_t kVersionMinor = 9;
constexpr size_t kFileHeaderBytes = 8;                // signature, major, minor, reserved u16
constexpr size_t kChunkOverheadBytes = 12;            // type, length, crc
constexpr uint32_t kMaxChunkPayloadBytes = 1u << 28;  // 256 MiB
constexpr int kMaxChunks = 65536;

// Packs "ABCD" so the bytes appear in that order in the file (little-endian u32).
constexpr uint32_t FourCC(const char (&s)[5]) {
  return uint32_t(uint8_t(s[0])) | uint32_t(uint8_t(s[1])) << 8 | uint32_t(uint8_t(s[2])) << 16 |
         uint32_t(uint8_t(s[3])) << 24;
}
constexpr uint32_t kChunkDone = FourCC("DONE");

inline bool IsCriticalChunk(uint32_t type) {
  const uint8_t first = uint8_t(type & 0xFF);
  return first >= 'A' && first <= 'Z';
}
// Writes the 4 characters and a terminating NUL into out[5] (for messages).
void ChunkTypeName(uint32_t type, char out[5]);

struct ChunkView {
  uint32_t type = 0;
  const uint8_t* data = nullptr;
  uint32_t size = 0;
  size_t offset = 0;  // file offset of the chunk's type field, for error messages
};

class ContainerReader {
 public:
  // Checks the signature and version. The buffer must outlive the reader and the chunk views.
  Status Open(const uint8_t* data, size_t size);
  uint8_t version_major() const { return major_; }
  uint8_t version_minor() const { return minor_; }
  // Reads the next chunk, checking its length against the bytes left, its type characters and
  // its CRC. Sets *done after the DONE chunk; bytes after it are an error.
  Status Next(ChunkView* chunk, bool* done);

 private:
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  size_t pos_ = 0;
  int chunks_read_ = 0;
  bool finished_ = false;
  uint8_t major_ = 0, minor_ = 0;
};

class ContainerWriter {
 public:
  explicit ContainerWriter(uint8_t version_minor = 0);
  void AddChunk(uint32_t type, const uint8_t* payload, size_t size);
  void AddChunk(uint32_t type, const std::vector<uint8_t>& payload) {
    AddChunk(type, payload.data(), payload.size());
  }
  // Appends DONE and returns the whole file.
  std::vector<uint8_t> Finish();

 private:
  std::vector<uint8_t> bytes_;
};

}  // namespace ecrf

#endif  // ECRF_FORMAT_CONTAINER_H_
