// Helpers shared by the coefficient coder's tests: a portable generator, every legal block
// shape, the expected end-of-block position and a stream hash for pinned bitstreams.
#ifndef ECRF_TESTS_COMMON_COEF_TEST_BLOCKS_H_
#define ECRF_TESTS_COMMON_COEF_TEST_BLOCKS_H_

#include <cstdint>
#include <vector>

#include "format/coefficients/coef_scan.h"

namespace ecrf {
namespace testing_blocks {

// Integer-only generator so that bit-exact expectations hold on every platform.
class SplitMix {
 public:
  explicit SplitMix(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  uint32_t Below(uint32_t n) { return static_cast<uint32_t>(Next() % n); }

 private:
  uint64_t state_;
};

inline std::vector<BlockShape> AllValidShapes() {
  std::vector<BlockShape> shapes;
  for (int n0 = 1; n0 <= 32; n0 *= 2) {
    for (int n1 = 1; n1 <= 32; n1 *= 2) {
      for (int n2 = 1; n2 <= 32; n2 *= 2) {
        const BlockShape shape{n0, n1, n2};
        if (IsValidBlockShape(shape)) shapes.push_back(shape);
      }
    }
  }
  return shapes;
}

inline int ExpectedEob(const BlockShape& shape, const std::vector<int32_t>& block) {
  const std::vector<uint16_t> scan = ComputeScanOrder(shape);
  int eob = shape.Volume();
  while (eob > 0 && block[scan[static_cast<size_t>(eob - 1)]] == 0) --eob;
  return eob;
}

inline uint64_t Fnv1a(const std::vector<uint8_t>& bytes) {
  uint64_t hash = 0xCBF29CE484222325ull;
  for (uint8_t b : bytes) hash = (hash ^ b) * 0x100000001B3ull;
  return hash;
}

}  // namespace testing_blocks
}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_COEF_TEST_BLOCKS_H_
