// CRC-32 as in zlib, PNG and IEEE 802.3 (reflected polynomial 0xEDB88320, initial value and final
// xor 0xFFFFFFFF). Check value: Crc32("123456789") == 0xCBF43926.
#ifndef ECRF_FORMAT_CRC32_H_
#define ECRF_FORMAT_CRC32_H_

#include <cstddef>
#include <cstdint>

namespace ecrf {

// Continue a running CRC: crc = Crc32Update(crc, a, na); crc = Crc32Update(crc, b, nb) equals
// Crc32 of a followed by b. Start from 0.
uint32_t Crc32Update(uint32_t crc, const uint8_t* data, size_t size);
inline uint32_t Crc32(const uint8_t* data, size_t size) { return Crc32Update(0, data, size); }

}  // namespace ecrf

#endif  // ECRF_FORMAT_CRC32_H_
