#include "trainer/model/alpha_mask.h"
#include "decoder/occupancy_rule.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>

namespace ecrf {
namespace trainer {

AlphaMask::AlphaMask(const Aabb& aabb, const std::array<int, 3>& res,
                     std::vector<uint8_t> occupancy)
    : aabb_(aabb), res_(res), occ_(std::move(occupancy)) {
  for (int a = 0; a < 3; ++a) {
    if (res[a] < 2) throw std::runtime_error("AlphaMask: resolution must be >= 2 per axis");
    if (!(aabb.max[a] > aabb.min[a])) throw std::runtime_error("AlphaMask: empty aabb");
    inv_size_[a] = 1.0f / (aabb.max[a] - aabb.min[a]) * 2.f;
  }
  const size_t X = res[0], Y = res[1], Z = res[2];
  if (occ_.size() != X * Y * Z) throw std::runtime_error("AlphaMask: occupancy size mismatch");
  count_ = 0;
  for (uint8_t v : occ_) {
    if (v > 1) throw std::runtime_error("AlphaMask: occupancy must be 0/1");
    count_ += v;
  }
  for (int a = 0; a < 3; ++a) blocks_[a] = ((res[a] - 2) >> kBlockShift) + 1;  // ceil(cells / 4)
  block_any_.assign(size_t(blocks_[0]) * blocks_[1] * blocks_[2], 0);
  cell_any_.assign((X - 1) * (Y - 1) * (Z - 1), 0);
  for (size_t z = 0; z + 1 < Z; ++z)
    for (size_t y = 0; y + 1 < Y; ++y)
      for (size_t x = 0; x + 1 < X; ++x) {
        uint8_t any = 0;
        for (int c = 0; c < 8; ++c)
          any |= occ_[((z + (c >> 2)) * Y + y + ((c >> 1) & 1)) * X + x + (c & 1)];
        cell_any_[(z * (Y - 1) + y) * (X - 1) + x] = any;
        block_any_[((z >> kBlockShift) * blocks_[1] + (y >> kBlockShift)) * blocks_[0] +
                   (x >> kBlockShift)] |= any;
      }
}

float AlphaMask::Sample(const float xyz[3]) const {
  if (occ_.empty()) return 0.f;
  float idx[3];
  for (int a = 0; a < 3; ++a) {
    const float c = (xyz[a] - aabb_.min[a]) * inv_size_[a] - 1.f;
    idx[a] = (c + 1.f) / 2.f * static_cast<float>(res_[a] - 1);
  }
  int i0[3];
  float f[3];
  for (int a = 0; a < 3; ++a) {
    const float fl = std::floor(idx[a]);
    if (!(fl > -2.f && fl < static_cast<float>(res_[a]))) return 0.f;
    i0[a] = static_cast<int>(fl);
    f[a] = idx[a] - fl;
  }
  float value = 0.f;
  for (int c = 0; c < 8; ++c) {
    const int x = i0[0] + (c & 1), y = i0[1] + ((c >> 1) & 1), z = i0[2] + (c >> 2);
    if (x < 0 || y < 0 || z < 0 || x >= res_[0] || y >= res_[1] || z >= res_[2]) continue;
    const float w = ((c & 1) ? f[0] : 1.f - f[0]) * (((c >> 1) & 1) ? f[1] : 1.f - f[1]) *
                    ((c >> 2) ? f[2] : 1.f - f[2]);
    value += w * occ_[(static_cast<size_t>(z) * res_[1] + y) * res_[0] + x];
  }
  return value;
}

bool AlphaMask::OccupiedSlow(const float idx[3]) const {
  return AnyWeightedCornerSet(idx, res_.data(), [this](int x, int y, int z) {
    return occ_[(static_cast<size_t>(z) * res_[1] + y) * res_[0] + x] != 0;
  });
}

bool AlphaMask::Occupied(const float xyz[3]) const {
  if (count_ == 0) return false;
  float idx[3];
  int i0[3];
  bool interior = true;
  for (int a = 0; a < 3; ++a) {
    const float c = (xyz[a] - aabb_.min[a]) * inv_size_[a] - 1.f;
    idx[a] = (c + 1.f) / 2.f * static_cast<float>(res_[a] - 1);
    // Strictly inside a cell: both corners along this axis carry weight.
    if (!(idx[a] > 0.f && idx[a] < static_cast<float>(res_[a] - 1))) {
      interior = false;
      continue;
    }
    i0[a] = static_cast<int>(idx[a]);
    if (static_cast<float>(i0[a]) == idx[a]) interior = false;
  }
  if (!interior) return OccupiedSlow(idx);
  if (!block_any_[((size_t(i0[2]) >> kBlockShift) * blocks_[1] + (i0[1] >> kBlockShift)) *
                      blocks_[0] +
                  (i0[0] >> kBlockShift)])
    return false;
  return cell_any_[(static_cast<size_t>(i0[2]) * (res_[1] - 1) + i0[1]) * (res_[0] - 1) + i0[0]] !=
         0;
}

std::array<int, 3> AlphaMaskRes(const std::array<int, 3>& grid_res, int downscale) {
  if (downscale < 1) throw std::invalid_argument("alpha-mask downscale must be >= 1");
  std::array<int, 3> res;
  for (int a = 0; a < 3; ++a) {
    const int cells = std::max(1, grid_res[a] - 1);
    res[a] = std::max(2, (cells + downscale - 1) / downscale + 1);
  }
  return res;
}

AlphaMask CoarsenAlphaMask(const AlphaMask& fine, int downscale) {
  const std::array<int, 3> res = AlphaMaskRes(fine.res(), downscale);
  // Per axis and fine index i: the coarse indices of the corners of the closed coarse cells
  // holding fine point i. Its coarse position u = i * (M - 1) / (R - 1) in exact integers: a point
  // on a coarse point needs only that point (it is a corner of every cell holding it).
  std::array<std::vector<std::array<int, 2>>, 3> range;
  for (int a = 0; a < 3; ++a) {
    const int64_t R = fine.res()[a], M = res[a];
    range[a].resize(size_t(R));
    for (int64_t i = 0; i < R; ++i) {
      const int64_t num = i * (M - 1), lo = num / (R - 1);
      const int64_t hi = (num % (R - 1) == 0) ? lo : lo + 1;
      range[a][size_t(i)] = {int(lo), int(std::min(hi, M - 1))};
    }
  }
  const int FX = fine.res()[0], FY = fine.res()[1], FZ = fine.res()[2];
  const size_t X = size_t(res[0]), Y = size_t(res[1]);
  std::vector<uint8_t> occ(X * Y * size_t(res[2]), 0);
  const uint8_t* in = fine.occupancy().data();
  for (int z = 0; z < FZ; ++z)
    for (int y = 0; y < FY; ++y) {
      const uint8_t* row = in + (size_t(z) * FY + y) * FX;
      for (int x = 0; x < FX; ++x) {
        if (!row[x]) continue;
        const auto& rx = range[0][size_t(x)];
        const auto& ry = range[1][size_t(y)];
        const auto& rz = range[2][size_t(z)];
        for (int cz = rz[0]; cz <= rz[1]; ++cz)
          for (int cy = ry[0]; cy <= ry[1]; ++cy)
            for (int cx = rx[0]; cx <= rx[1]; ++cx) occ[(size_t(cz) * Y + cy) * X + cx] = 1;
      }
    }
  return AlphaMask(fine.aabb(), res, std::move(occ));
}

}  // namespace trainer
}  // namespace ecrf
