// The encoder half of the container (SPEC.md 3): signature, chunks with their CRC, DONE.
#include "format/container.h"

#include "format/byte_io.h"
#include "format/crc32.h"

namespace ecrf {

ContainerWriter::ContainerWriter(uint8_t version_minor) {
  bytes_.assign(kSignature, kSignature + 4);
  bytes_.push_back(kVersionMajor);
  bytes_.push_back(version_minor);
  bytes_.push_back(0);
  bytes_.push_back(0);
}

void ContainerWriter::AddChunk(uint32_t type, const uint8_t* payload, size_t size) {
  ByteWriter w;
  w.U32(type);
  w.U32(uint32_t(size));
  w.Bytes(payload, size);
  w.U32(Crc32(w.bytes().data(), w.size()));
  bytes_.insert(bytes_.end(), w.bytes().begin(), w.bytes().end());
}

std::vector<uint8_t> ContainerWriter::Finish() {
  AddChunk(kChunkDone, nullptr, 0);
  std::vector<uint8_t> out;
  out.swap(bytes_);
  return out;
}

}  // namespace ecrf
