// The checksums of a decoded scene (SPEC.md 6.5): the grids (MD5 over each tensor's float32 values,
// little endian, in storage order; the scene checksum covers all twelve tensors in chunk order),
// the occupancy mask (its packed bits) and the MLP parameters (float32, the MLPW order).
#ifndef ECRF_CONFORMANCE_GRID_MD5_H_
#define ECRF_CONFORMANCE_GRID_MD5_H_

#include <cstring>
#include <string>
#include <vector>

#include "conformance/md5.h"
#include "decoder/field.h"

namespace ecrf {
namespace conformance {

inline void AddTensorToMd5(const dec::VmGrid& grid, int tensor, conformance::Md5* md5) {
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
  conformance::Md5 md5;
  AddTensorToMd5(grid, tensor, &md5);
  return md5.HexDigest();
}

inline std::string SceneGridMd5(const dec::SceneField& scene) {
  conformance::Md5 md5;
  for (const dec::VmGrid* g : {&scene.density, &scene.appearance}) {
    for (int t = 0; t < 6; ++t) AddTensorToMd5(*g, t, &md5);
  }
  return md5.HexDigest();
}

// MD5 of the packed mask bits (x fastest, LSB first, unused high bits 0); of no bytes without a
// mask.
inline std::string OccupancyMd5(const dec::SceneField& scene) {
  conformance::Md5 md5;
  if (scene.has_mask) {
    const size_t bytes = (scene.mask.voxel_count() + 7) / 8;
    std::vector<uint8_t> packed(scene.mask.bits(), scene.mask.bits() + bytes);
    const size_t tail = scene.mask.voxel_count() % 8;
    if (tail != 0) packed.back() = uint8_t(packed.back() & ((1u << tail) - 1));
    md5.Update(packed.data(), packed.size());
  }
  return md5.HexDigest();
}

// MD5 of the MLP parameters as float32 little endian in the MLPW order; "" if there is no MLP.
inline std::string MlpMd5(const dec::SceneField& scene) {
  if (!scene.mlp.initialized()) return "";
  std::vector<float> params(scene.mlp.num_params());
  if (!scene.mlp.GetParams(params.data(), params.size()).ok()) return "";
  std::vector<uint8_t> bytes(params.size() * 4);
  for (size_t i = 0; i < params.size(); ++i) {
    uint32_t u;
    std::memcpy(&u, &params[i], 4);
    for (int b = 0; b < 4; ++b) bytes[i * 4 + b] = uint8_t(u >> (8 * b));
  }
  conformance::Md5 md5;
  md5.Update(bytes.data(), bytes.size());
  return md5.HexDigest();
}

}  // namespace conformance
}  // namespace ecrf

#endif  // ECRF_CONFORMANCE_GRID_MD5_H_
