// An axis-aligned box in world coordinates: the region a model covers, fitted from the cameras
// (trainer/data/scene_fit.h) and shrunk to the occupied voxels during training.
#ifndef ECRF_TRAINER_DATA_AABB_H_
#define ECRF_TRAINER_DATA_AABB_H_

#include <array>

namespace ecrf {
namespace trainer {

struct Aabb {
  std::array<float, 3> min{{-1.5f, -1.5f, -1.5f}};
  std::array<float, 3> max{{1.5f, 1.5f, 1.5f}};
};

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_DATA_AABB_H_
