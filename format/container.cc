#include "format/container.h"

#include "format/byte_io.h"
#include "format/crc32.h"

namespace ecrf {

namespace {

bool IsValidTypeChar(uint8_t c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == ' ';
}

}  // namespace

void ChunkTypeName(uint32_t type, char out[5]) {
  for (int i = 0; i < 4; ++i) {
    const uint8_t c = uint8_t(type >> (8 * i));
    out[i] = IsValidTypeChar(c) ? char(c) : '?';
  }
  out[4] = '\0';
}

Status ContainerReader::Open(const uint8_t* data, size_t size) {
  ECRF_CHECK_OR_RETURN(data != nullptr || size == 0, kErrInvalidArgument, "null buffer");
  data_ = data;
  size_ = size;
  pos_ = 0;
  chunks_read_ = 0;
  finished_ = false;
  ByteReader r(data, size);
  const uint8_t* sig = nullptr;
  ECRF_RETURN_IF_ERROR(r.ReadBytes(4, &sig, "file signature"));
  for (int i = 0; i < 4; ++i) {
    ECRF_CHECK_OR_RETURN(sig[i] == kSignature[i], kErrCorrupt,
                         "file signature: byte %d is 0x%02x, expected 0x%02x ('ECRF'): not an "
                         ".ecrf stream",
                         i, sig[i], kSignature[i]);
  }
  uint16_t reserved = 0;
  ECRF_RETURN_IF_ERROR(r.ReadU8(&major_, "version_major"));
  ECRF_RETURN_IF_ERROR(r.ReadU8(&minor_, "version_minor"));
  ECRF_RETURN_IF_ERROR(r.ReadU16(&reserved, "header reserved field"));
  ECRF_CHECK_OR_RETURN(major_ == kVersionMajor, kErrUnsupported,
                       "version %u.%u: this decoder reads major version %u only", major_, minor_,
                       kVersionMajor);
  ECRF_CHECK_OR_RETURN(reserved == 0, kErrCorrupt, "header reserved field is %u, must be 0",
                       reserved);
  pos_ = r.position();
  return Status::Ok();
}

Status ContainerReader::Next(ChunkView* chunk, bool* done) {
  *done = false;
  ECRF_CHECK_OR_RETURN(data_ != nullptr, kErrInvalidArgument, "container not opened");
  ECRF_CHECK_OR_RETURN(!finished_, kErrInvalidArgument, "read past the DONE chunk");
  if (pos_ == size_) {
    return Status::Error(kErrTruncated, "stream ends at offset %zu without a DONE chunk", pos_);
  }
  ECRF_CHECK_OR_RETURN(chunks_read_ < kMaxChunks, kErrLimit, "more than %d chunks", kMaxChunks);
  ByteReader r(data_ + pos_, size_ - pos_);
  uint32_t type = 0, length = 0;
  ECRF_RETURN_IF_ERROR(r.ReadU32(&type, "chunk type"));
  ECRF_RETURN_IF_ERROR(r.ReadU32(&length, "chunk length"));
  char name[5];
  ChunkTypeName(type, name);
  for (int i = 0; i < 4; ++i) {
    ECRF_CHECK_OR_RETURN(IsValidTypeChar(uint8_t(type >> (8 * i))), kErrCorrupt,
                         "chunk at offset %zu: type byte %d is not a letter, digit or space", pos_,
                         i);
  }
  ECRF_CHECK_OR_RETURN(length <= kMaxChunkPayloadBytes, kErrLimit,
                       "chunk '%s' at offset %zu: length %u exceeds the limit of %u bytes", name,
                       pos_, length, kMaxChunkPayloadBytes);
  // Length is checked against what is left before anything is read from the payload.
  if (r.remaining() < size_t(length) + 4) {
    return Status::Error(kErrTruncated,
                         "chunk '%s' at offset %zu: length %u plus CRC needs %zu bytes, %zu left",
                         name, pos_, length, size_t(length) + 4, r.remaining());
  }
  const uint8_t* payload = nullptr;
  uint32_t stored_crc = 0;
  ECRF_RETURN_IF_ERROR(r.ReadBytes(length, &payload, "chunk payload"));
  ECRF_RETURN_IF_ERROR(r.ReadU32(&stored_crc, "chunk CRC"));
  const uint32_t crc = Crc32(data_ + pos_, 8 + size_t(length));
  ECRF_CHECK_OR_RETURN(crc == stored_crc, kErrChecksum,
                       "chunk '%s' at offset %zu: CRC 0x%08x, stored 0x%08x: the chunk is damaged",
                       name, pos_, crc, stored_crc);
  chunk->type = type;
  chunk->data = payload;
  chunk->size = length;
  chunk->offset = pos_;
  pos_ += r.position();
  ++chunks_read_;
  if (type == kChunkDone) {
    ECRF_CHECK_OR_RETURN(length == 0, kErrCorrupt, "DONE chunk at offset %zu has %u payload bytes",
                         chunk->offset, length);
    ECRF_CHECK_OR_RETURN(pos_ == size_, kErrCorrupt,
                         "%zu bytes follow the DONE chunk at offset %zu", size_ - pos_,
                         chunk->offset);
    finished_ = true;
    *done = true;
  }
  return Status::Ok();
}

}  // namespace ecrf
