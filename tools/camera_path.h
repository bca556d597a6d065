// Camera paths for `ecrf render`: the orbit (--orbit N) and the spiral (--spiral N) around the
// origin. Both are made of the decoder's orbit cameras (decoder/camera.h: +z up, looking at the
// origin, Blender's field of view), so an orbit here is bit for bit the web viewer's and the
// Python module's, and frame 0 of a spiral is frame 0 of the orbit with the same settings.
#ifndef ECRF_TOOLS_CAMERA_PATH_H_
#define ECRF_TOOLS_CAMERA_PATH_H_

#include <string>
#include <vector>

#include "trainer/data/camera.h"

namespace ecrf {
namespace tools {

// One camera of a path; `name` is the PNG's name without ".png".
struct PathCamera {
  std::string name;
  trainer::Camera camera;
};

// Frame k of a path called `prefix` is PREFIX_%03d ("orbit_007", "orbit_1234"): the names sort
// in path order up to 1000 frames and match ffmpeg's image-sequence pattern PREFIX_%03d.png at
// any count.
std::string FrameName(const std::string& prefix, int k);
std::string FramePattern(const std::string& prefix);  // "orbit_%03d"

// The circle the orbit follows and the spiral oscillates about.
struct OrbitShape {
  int width = 400, height = 400;  // image size in pixels
  double radius = 4.0;            // distance from the origin, scene units
  double elevation_deg = 30.0;    // above the xy plane
};

// How far the spiral leaves the orbit's circle (see SpiralPose).
struct SpiralShape {
  double elevation_amplitude_deg = 15.0;
  double radius_amplitude = 0.1;  // a fraction of OrbitShape::radius
  int cycles = 2;                 // up-and-down swings per turn; whole, so the path loops
};

// Where an orbit camera sits: it looks at the origin from these spherical coordinates.
struct OrbitPose {
  double azimuth_deg = 0.0, elevation_deg = 0.0, radius = 1.0;
};

// Frame k of N on the orbit: azimuth 360 k / N, the shape's elevation and radius.
OrbitPose OrbitPoseAt(int k, int frames, const OrbitShape& orbit);

// Frame k of N on the spiral, with t = k / N and p = sin(2 pi cycles t):
//   azimuth   = 360 t                                        (one turn, as the orbit)
//   elevation = orbit.elevation_deg + elevation_amplitude_deg * p
//   radius    = orbit.radius * (1 + radius_amplitude * p)
// The camera rises and pulls back together, then dips and comes closer (the swing of LLFF's and
// nerfstudio's spiral renders, on a sphere around an object instead of in front of a capture).
// t = 0 gives the orbit's first camera, and whole cycles make frame N equal frame 0, so a video
// of the path loops without a jump.
OrbitPose SpiralPoseAt(int k, int frames, const OrbitShape& orbit, const SpiralShape& spiral);

// "" when the spiral stays clear of the poles (|elevation| + amplitude < 90: the up vector +z is
// undefined straight above the origin) and of the origin (radius amplitude in [0, 1)); else the
// problem, naming the flags.
std::string SpiralProblem(const OrbitShape& orbit, const SpiralShape& spiral);

// The decoder's orbit camera (decoder/camera.h) for a pose, as a trainer camera.
trainer::Camera OrbitView(int width, int height, const OrbitPose& pose);

// `frames` cameras named orbit_000... / spiral_000....
std::vector<PathCamera> OrbitPath(int frames, const OrbitShape& orbit);
std::vector<PathCamera> SpiralPath(int frames, const OrbitShape& orbit, const SpiralShape& spiral);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_CAMERA_PATH_H_
