#include "format/byte_io.h"

namespace ecrf {

Status ByteReader::ReadI32(int32_t* v, const char* what) {
  uint32_t u = 0;
  ECRF_RETURN_IF_ERROR(ReadU32(&u, what));
  std::memcpy(v, &u, 4);
  return Status::Ok();
}

Status ByteReader::ReadF32(float* v, const char* what) {
  uint32_t u = 0;
  ECRF_RETURN_IF_ERROR(ReadU32(&u, what));
  std::memcpy(v, &u, 4);
  return Status::Ok();
}

Status ByteReader::ReadBytes(size_t n, const uint8_t** out, const char* what) {
  if (remaining() < n) {
    return Status::Error(kErrTruncated, "%s: needs %zu bytes at offset %zu, %zu left", what, n,
                         pos_, remaining());
  }
  *out = data_ + pos_;
  pos_ += n;
  return Status::Ok();
}

}  // namespace ecrf
