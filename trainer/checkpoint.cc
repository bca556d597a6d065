#include "trainer/checkpoint.h"

#include <zstd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <unistd.h>

namespace ecrf {
namespace trainer {
namespace {

constexpr char kMagic[8] = {'E', 'C', 'R', 'F', 'C', 'K', 'P', '1'};
constexpr uint64_t kMaxArrays = 1 << 16;

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

void WriteFileAtomically(const std::string& path, const void* bytes, size_t size) {
  const std::string tmp = path + ".tmp." + std::to_string(getpid());
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw std::runtime_error(tmp + ": cannot create: " + std::strerror(errno));
  const bool written = std::fwrite(bytes, 1, size, f) == size;
  const bool flushed = std::fflush(f) == 0 && fsync(fileno(f)) == 0;
  const bool closed = std::fclose(f) == 0;
  if (!written || !flushed || !closed) {
    std::remove(tmp.c_str());
    throw std::runtime_error(tmp + ": write failed: " + std::strerror(errno));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot replace: " + std::strerror(errno));
  }
}

std::vector<uint8_t> ReadWholeFile(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  std::vector<uint8_t> bytes;
  uint8_t buffer[1 << 16];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), f)) > 0) bytes.insert(bytes.end(), buffer, buffer + n);
  const bool failed = std::ferror(f);
  std::fclose(f);
  if (failed) throw std::runtime_error(path + ": read error");
  return bytes;
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
  const size_t z = ZSTD_compress(out.data() + header, out.size() - header, raw.data(), raw.size(),
                                 zstd_level);
  if (ZSTD_isError(z)) throw std::runtime_error(path + ": zstd: " + ZSTD_getErrorName(z));
  out.resize(header + z);
  WriteFileAtomically(path, out.data(), out.size());
}

Checkpoint ReadCheckpoint(const std::string& path) {
  const std::vector<uint8_t> file = ReadWholeFile(path);
  if (file.size() < 16 || std::memcmp(file.data(), kMagic, 8) != 0) {
    throw std::runtime_error(path + ": not an ecrf checkpoint (bad magic)");
  }
  uint64_t raw_size;
  std::memcpy(&raw_size, file.data() + 8, 8);
  const unsigned long long frame = ZSTD_getFrameContentSize(file.data() + 16, file.size() - 16);
  if (frame == ZSTD_CONTENTSIZE_ERROR || frame == ZSTD_CONTENTSIZE_UNKNOWN || frame != raw_size) {
    throw std::runtime_error(path + ": checkpoint is damaged (zstd frame size)");
  }
  std::vector<uint8_t> raw(raw_size);
  const size_t n = ZSTD_decompress(raw.data(), raw.size(), file.data() + 16, file.size() - 16);
  if (ZSTD_isError(n) || n != raw_size) {
    throw std::runtime_error(path + ": checkpoint is damaged: " +
                             (ZSTD_isError(n) ? ZSTD_getErrorName(n) : "size mismatch"));
  }
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
    if (dims > 8) throw std::runtime_error(path + ": array '" + a.name + "' has too many dimensions");
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
