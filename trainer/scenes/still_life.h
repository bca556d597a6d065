// The still life the procedural scenes show: a checkered slab carrying two spheres and two
// boxes around the origin (z up), lit by one directional light with cast shadows.
#ifndef ECRF_TRAINER_SCENES_STILL_LIFE_H_
#define ECRF_TRAINER_SCENES_STILL_LIFE_H_

#include "trainer/scenes/procedural_math.h"

namespace ecrf::trainer::procedural {

// Everything lies within this sphere about the origin.
inline constexpr double kStillLifeRadius = 1.7;
// Underside of the slab, the lowest point of the still life.
inline constexpr double kStillLifeBottom = -0.55;

// Unit vector towards the light.
Vec3 StillLifeLight();

// Colour seen along the ray (unit `dir`) when it hits the still life: ambient plus Lambertian
// plus a Blinn-Phong highlight, shadowed by the still life itself. False when it misses.
bool ShadeStillLife(Vec3 origin, Vec3 dir, Vec3* colour);

// Distance along the ray (unit `dir`) to the surface ShadeStillLife shades; false when it misses.
bool StillLifeHitDistance(Vec3 origin, Vec3 dir, double* t);

// Whether the ray hits any part of the still life (shadow rays of surfaces around it).
bool StillLifeOccludes(Vec3 origin, Vec3 dir);

}  // namespace ecrf::trainer::procedural

#endif  // ECRF_TRAINER_SCENES_STILL_LIFE_H_
