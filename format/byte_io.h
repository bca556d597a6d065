// Little-endian byte reading and writing. The reader checks every read against the bytes left
// and fails with a status instead of reading past the end (the decoder never trusts a length).
#ifndef ECRF_FORMAT_BYTE_IO_H_
#define ECRF_FORMAT_BYTE_IO_H_

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "format/status.h"

namespace ecrf {

class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size) : data_(data), size_(size), pos_(0) {}

  size_t position() const { return pos_; }
  size_t remaining() const { return size_ - pos_; }
  const uint8_t* current() const { return data_ + pos_; }

  Status ReadU8(uint8_t* v, const char* what) { return ReadLe(v, 1, what); }
  Status ReadU16(uint16_t* v, const char* what) { return ReadLe(v, 2, what); }
  Status ReadU32(uint32_t* v, const char* what) { return ReadLe(v, 4, what); }
  Status ReadI32(int32_t* v, const char* what);
  Status ReadF32(float* v, const char* what);
  Status ReadBytes(size_t n, const uint8_t** out, const char* what);
  Status Skip(size_t n, const char* what) {
    const uint8_t* unused = nullptr;
    return ReadBytes(n, &unused, what);
  }

 private:
  template <typename T>
  Status ReadLe(T* v, size_t n, const char* what) {
    if (remaining() < n) {
      return Status::Error(kErrTruncated, "%s: needs %zu bytes at offset %zu, %zu left", what, n,
                           pos_, remaining());
    }
    T r = 0;
    for (size_t i = 0; i < n; ++i) r = T(r | T(T(data_[pos_ + i]) << (8 * i)));
    pos_ += n;
    *v = r;
    return Status::Ok();
  }

  const uint8_t* data_;
  size_t size_;
  size_t pos_;
};

class ByteWriter {
 public:
  void U8(uint8_t v) { bytes_.push_back(v); }
  void U16(uint16_t v) { Le(v, 2); }
  void U32(uint32_t v) { Le(v, 4); }
  void I32(int32_t v) { Le(uint32_t(v), 4); }
  void F32(float v) {
    uint32_t u;
    std::memcpy(&u, &v, 4);
    Le(u, 4);
  }
  void Bytes(const uint8_t* data, size_t n) { bytes_.insert(bytes_.end(), data, data + n); }
  void Bytes(const std::vector<uint8_t>& v) { Bytes(v.data(), v.size()); }
  std::vector<uint8_t>& bytes() { return bytes_; }
  size_t size() const { return bytes_.size(); }

 private:
  void Le(uint32_t v, int n) {
    for (int i = 0; i < n; ++i) bytes_.push_back(uint8_t(v >> (8 * i)));
  }
  std::vector<uint8_t> bytes_;
};

}  // namespace ecrf

#endif  // ECRF_FORMAT_BYTE_IO_H_
