// The room around the capture scene's still life: a closed box with procedural textures.
#ifndef ECRF_TRAINER_SCENES_CAPTURE_ROOM_H_
#define ECRF_TRAINER_SCENES_CAPTURE_ROOM_H_

#include "trainer/scenes/procedural_math.h"

namespace ecrf::trainer::procedural {

// Colour where a ray starting inside the room (unit `dir`) leaves it: plank floor (with the
// still life's shadow), a tiled ceiling and four walls that each look different (striped
// wallpaper, brick, a window, a diamond pattern) so that every view is recognisable. Rays
// starting outside the room get the colour of the far wall they would reach.
Vec3 ShadeRoom(const double room_min[3], const double room_max[3], Vec3 origin, Vec3 dir);

// Distance along the ray (unit `dir`) to the point of the room's walls, floor or ceiling that
// ShadeRoom shades.
double RoomExitDistance(const double room_min[3], const double room_max[3], Vec3 origin, Vec3 dir);

}  // namespace ecrf::trainer::procedural

#endif  // ECRF_TRAINER_SCENES_CAPTURE_ROOM_H_
