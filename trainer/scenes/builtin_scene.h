// A procedural scene that needs no files, for smoke tests and CI training runs.
#ifndef ECRF_TRAINER_SCENES_BUILTIN_SCENE_H_
#define ECRF_TRAINER_SCENES_BUILTIN_SCENE_H_

#include <cstdint>
#include <string>

#include "trainer/data/dataset.h"

namespace ecrf::trainer {

// Field of view of the builtin cameras (both axes for square images), in radians (40 degrees).
inline constexpr double kBuiltinFieldOfView = 0.6981317007977318;
// Distance of the builtin cameras from the origin, which they look at.
inline constexpr double kBuiltinCameraDistance = 4.0;

// Renders `num_views` width x height views of a small still life inside [-1.5, 1.5]^3 (z up,
// like the Blender scenes): a checkered slab carrying a checkered sphere, a striped sphere, a
// gridded box and a tall striped box, lit by a directional light with cast shadows, Lambertian
// plus a Blinn-Phong highlight (so colour depends on the view), on a white background, with
// 2x2 supersampling. Exact ray-sphere/box intersection, so it is fast: 100 views of 100x100
// take well under a second.
// Cameras sit on a sphere of radius 4 looking at the origin with a 40 degree field of view:
//   "train": random positions on the upper hemisphere (elevation ~6 to ~72 degrees) from `seed`;
//   "test":  an orbit at 30 degrees elevation, phase from `seed`;
//   "val":   an orbit at 50 degrees elevation.
// The dataset uses the Blender conventions: aabb [-1.5, 1.5]^3, near 2, far 6, white background.
// Deterministic for given arguments. Throws std::runtime_error for a bad split or sizes.
Dataset MakeBuiltinScene(const std::string& split, int width, int height, int num_views,
                         uint32_t seed);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_SCENES_BUILTIN_SCENE_H_
