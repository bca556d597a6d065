#include "trainer/train/checkpoint.h"

#include <zstd.h>

#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "trainer/data/file_io.h"

namespace ecrf {
namespace trainer {
namespace {

// Version 2 frames carry zstd's content checksum (XXH64 of the uncompressed bytes), so a damaged
// checkpoint is refused when read instead of resuming with altered weights; version 1 files
// (without it) are still read.
constexpr char kMagic[8] = {'E', 'C', 'R', 'F', 'C', 'K', 'P', '2'};
constexpr char kMagicV1[8] = {'E', 'C', 'R', 'F', 'C', 'K', 'P', '1'};
constexpr uint64_t kMaxArrays = 1 << 16;
// Larger than any model this trainer builds (the paper preset's checkpoint is ~0.3 GB); a size
// field beyond it is damage, refused before anything is allocated.
constexpr uint64_t kMaxRawBytes = uint64_t(16) << 30;
// Trained weights and Adam moments compress by less than 2x; a frame that claims to expand more
// than this (beyond a small allowance for near-empty models) is a bomb, refused before it is
// decompressed.
constexpr uint64_t kMaxExpansion = 1000;
constexpr uint64_t kExpansionAllowance = uint64_t(64) << 20;

void Put(std::vector<uint8_t>& out, const void* p, size_t n) {
  const uint8_t* b = static_cast<const uint8_t*>(p);
  out.insert(out.end(), b, b + n);
}
void PutU64(std::vector<uint8_t>& out, uint64_t v) { Put(out, &v, 8); }

struct Cursor {
  const std::vector<uint8_t>& bytes;
  size_t pos;
  const std::string& path;
  void Get(void* p, size_t n) {
    if (bytes.size() - pos < n) {
      throw std::runtime_error(path + ": checkpoint is truncated at byte " + std::to_string(pos));
    }
    std::memcpy(p, bytes.data() + pos, n);
    pos += n;
  }
  uint64_t U64() {
    uint64_t v;
    Get(&v, 8);
    return v;
  }
  void CheckRemaining(uint64_t n, const char* what) {
    if (n > bytes.size() - pos) {
      throw std::runtime_error(path + ": checkpoint " + what + " claims " + std::to_string(n) +
                               " bytes, only " + std::to_string(bytes.size() - pos) + " left");
    }
  }
};

}  // namespace

const CheckpointArray* Checkpoint::Find(const std::string& name) const {
  for (const CheckpointArray& a : arrays) {
    if (a.name == name) return &a;
  }
  return nullptr;
}

void WriteCheckpoint(const std::string& path, const Checkpoint& checkpoint, int zstd_level) {
  std::vector<uint8_t> raw;
  PutU64(raw, checkpoint.json.size());
  Put(raw, checkpoint.json.data(), checkpoint.json.size());
  PutU64(raw, checkpoint.arrays.size());
  for (const CheckpointArray& a : checkpoint.arrays) {
    uint64_t count = 1;
    for (int64_t d : a.shape) count *= uint64_t(d);
    if (count != a.data.size()) {
      throw std::logic_error("checkpoint array '" + a.name + "': shape does not match its data");
    }
    PutU64(raw, a.name.size());
    Put(raw, a.name.data(), a.name.size());
    PutU64(raw, a.shape.size());
    for (int64_t d : a.shape) PutU64(raw, uint64_t(d));
    Put(raw, a.data.data(), a.data.size() * sizeof(float));
  }
  std::vector<uint8_t> out(kMagic, kMagic + 8);
  PutU64(out, raw.size());
  const size_t header = out.size();
  out.resize(header + ZSTD_compressBound(raw.size()));
  ZSTD_CCtx* cctx = ZSTD_createCCtx();
  if (!cctx) throw std::runtime_error(path + ": zstd: out of memory");
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_compressionLevel, zstd_level);
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 1);
  const size_t z =
      ZSTD_compress2(cctx, out.data() + header, out.size() - header, raw.data(), raw.size());
  ZSTD_freeCCtx(cctx);
  if (ZSTD_isError(z)) throw std::runtime_error(path + ": zstd: " + ZSTD_getErrorName(z));
  out.resize(header + z);
  WriteFileAtomically(path, out.data(), out.size());
}

namespace {

// Decompresses one frame, growing the output with what actually decompresses (a damaged size
// field cannot make it allocate more than the frame really holds, and never over raw_size).
std::vector<uint8_t> Decompress(const std::string& path, const uint8_t* data, size_t size,
                                uint64_t raw_size) {
  std::vector<uint8_t> raw;
  ZSTD_DCtx* dctx = ZSTD_createDCtx();
  if (!dctx) throw std::runtime_error(path + ": zstd: out of memory");
  ZSTD_inBuffer in{data, size, 0};
  std::string error;
  for (size_t status = 1; status != 0 && error.empty();) {
    const size_t chunk = size_t(std::min<uint64_t>(raw_size - raw.size(), uint64_t(64) << 20));
    const size_t before = raw.size();
    raw.resize(before +
               std::max<size_t>(chunk, 1));  // one spare byte finds a frame longer than said
    ZSTD_outBuffer out{raw.data() + before, raw.size() - before, 0};
    status = ZSTD_decompressStream(dctx, &out, &in);
    raw.resize(before + out.pos);
    if (ZSTD_isError(status)) {
      error = ZSTD_getErrorName(status);
    } else if (raw.size() > raw_size) {
      error = "it holds more than its header says";
    } else if (status != 0 && in.pos == in.size && out.pos < out.size) {
      error = "it ends inside its zstd frame";
    }
  }
  ZSTD_freeDCtx(dctx);
  if (error.empty() && in.pos != size) {
    error = std::to_string(size - in.pos) + " bytes follow its zstd frame";
  } else if (error.empty() && raw.size() != raw_size) {
    error = "it holds " + std::to_string(raw.size()) + " bytes, its header says " +
            std::to_string(raw_size);
  }
  if (!error.empty()) throw std::runtime_error(path + ": checkpoint is damaged: " + error);
  return raw;
}

}  // namespace

Checkpoint ReadCheckpoint(const std::string& path) {
  const std::vector<uint8_t> file = ReadWholeFile(path);
  const bool v1 = file.size() >= 8 && std::memcmp(file.data(), kMagicV1, 8) == 0;
  if (file.size() < 16 || (std::memcmp(file.data(), kMagic, 8) != 0 && !v1)) {
    throw std::runtime_error(path + ": not an ecrf checkpoint (bad magic)");
  }
  uint64_t raw_size;
  std::memcpy(&raw_size, file.data() + 8, 8);
  const unsigned long long frame = ZSTD_getFrameContentSize(file.data() + 16, file.size() - 16);
  if (frame == ZSTD_CONTENTSIZE_ERROR || frame == ZSTD_CONTENTSIZE_UNKNOWN || frame != raw_size ||
      raw_size > kMaxRawBytes) {
    throw std::runtime_error(path + ": checkpoint is damaged (zstd frame size)");
  }
  const uint64_t compressed = file.size() - 16;
  if (raw_size > kExpansionAllowance && raw_size / kMaxExpansion > compressed) {
    throw std::runtime_error(path + ": checkpoint is damaged: its " + std::to_string(compressed) +
                             "-byte zstd frame claims " + std::to_string(raw_size) +
                             " bytes, more than " + std::to_string(kMaxExpansion) +
                             " times its size");
  }
  // RFC 8878 3.1.1.1.1: bit 2 of the frame header descriptor (after the 4-byte frame magic).
  if (!v1 && (file.size() < 21 || !(file[16 + 4] & 0x04))) {
    throw std::runtime_error(path + ": checkpoint is damaged (its zstd frame has no checksum)");
  }
  const std::vector<uint8_t> raw = Decompress(path, file.data() + 16, file.size() - 16, raw_size);
  Cursor c{raw, 0, path};
  Checkpoint ck;
  const uint64_t json_size = c.U64();
  c.CheckRemaining(json_size, "json");
  ck.json.assign(reinterpret_cast<const char*>(raw.data() + c.pos), json_size);
  c.pos += json_size;
  const uint64_t count = c.U64();
  if (count > kMaxArrays) throw std::runtime_error(path + ": too many arrays in checkpoint");
  for (uint64_t i = 0; i < count; ++i) {
    CheckpointArray a;
    const uint64_t name_size = c.U64();
    c.CheckRemaining(name_size, "array name");
    a.name.assign(reinterpret_cast<const char*>(raw.data() + c.pos), name_size);
    c.pos += name_size;
    const uint64_t dims = c.U64();
    if (dims > 8)
      throw std::runtime_error(path + ": array '" + a.name + "' has too many dimensions");
    uint64_t elements = 1;
    for (uint64_t d = 0; d < dims; ++d) {
      const uint64_t extent = c.U64();
      if (extent > (uint64_t(1) << 40) || (extent && elements > (uint64_t(1) << 40) / extent)) {
        throw std::runtime_error(path + ": array '" + a.name + "' is implausibly large");
      }
      a.shape.push_back(int64_t(extent));
      elements *= extent;
    }
    c.CheckRemaining(elements * sizeof(float), "array data");
    a.data.resize(elements);
    c.Get(a.data.data(), elements * sizeof(float));
    ck.arrays.push_back(std::move(a));
  }
  return ck;
}

}  // namespace trainer
}  // namespace ecrf
