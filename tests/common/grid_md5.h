// The checksum of a decoded scene's grids (SPEC.md 6.5): MD5 over each tensor's float32 values,
// little endian, in storage order; the scene checksum covers all twelve tensors in chunk order.
#ifndef ECRF_TESTS_COMMON_GRID_MD5_H_
#define ECRF_TESTS_COMMON_GRID_MD5_H_

#include <cstring>
#include <string>

#include "decoder/field.h"
#include "tests/common/md5.h"

namespace ecrf {
namespace conformance {

inline void AddTensorToMd5(const dec::VmGrid& grid, int tensor, testing_md5::Md5* md5) {
  const int m = tensor % 3;
  const float* data = tensor < 3 ? grid.plane_f32[m].data() : grid.line_f32[m].data();
  const size_t count = tensor < 3 ? grid.plane_count(m) : grid.line_count(m);
  uint8_t buffer[4096 * 4];
  size_t fill = 0;
  for (size_t i = 0; i < count; ++i) {
    uint32_t u;
    std::memcpy(&u, &data[i], 4);
    for (int b = 0; b < 4; ++b) buffer[fill++] = uint8_t(u >> (8 * b));
    if (fill == sizeof(buffer)) {
      md5->Update(buffer, fill);
      fill = 0;
    }
  }
  md5->Update(buffer, fill);
}

inline std::string TensorMd5(const dec::VmGrid& grid, int tensor) {
  testing_md5::Md5 md5;
  AddTensorToMd5(grid, tensor, &md5);
  return md5.HexDigest();
}

inline std::string SceneGridMd5(const dec::SceneField& scene) {
  testing_md5::Md5 md5;
  for (const dec::VmGrid* g : {&scene.density, &scene.appearance}) {
    for (int t = 0; t < 6; ++t) AddTensorToMd5(*g, t, &md5);
  }
  return md5.HexDigest();
}

}  // namespace conformance
}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_GRID_MD5_H_
