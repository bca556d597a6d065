#include "tools/camera_path.h"

#include <cmath>
#include <cstdio>

#include "decoder/camera.h"

namespace ecrf {
namespace tools {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

std::string FrameName(const std::string& prefix, int k) {
  char number[16];
  std::snprintf(number, sizeof(number), "_%03d", k);
  return prefix + number;
}

std::string FramePattern(const std::string& prefix) { return prefix + "_%03d"; }

OrbitPose OrbitPoseAt(int k, int frames, const OrbitShape& orbit) {
  // 360.0 * k / N, not k * (360.0 / N): the expression `ecrf render --orbit` always used, so
  // existing orbits keep their last bit.
  return {360.0 * k / frames, orbit.elevation_deg, orbit.radius};
}

OrbitPose SpiralPoseAt(int k, int frames, const OrbitShape& orbit, const SpiralShape& spiral) {
  const double t = double(k) / frames;
  const double p = std::sin(2.0 * kPi * spiral.cycles * t);
  return {360.0 * k / frames, orbit.elevation_deg + spiral.elevation_amplitude_deg * p,
          orbit.radius * (1.0 + spiral.radius_amplitude * p)};
}

std::string SpiralProblem(const OrbitShape& orbit, const SpiralShape& spiral) {
  if (!(spiral.elevation_amplitude_deg >= 0.0)) return "--spiral-elevation must be >= 0";
  if (!(spiral.radius_amplitude >= 0.0 && spiral.radius_amplitude < 1.0))
    return "--spiral-radius must be in [0, 1) (a fraction of --radius)";
  const double highest = std::abs(orbit.elevation_deg) + spiral.elevation_amplitude_deg;
  if (!(highest < 90.0)) {
    char text[200];
    std::snprintf(text, sizeof(text),
                  "--elevation %g with --spiral-elevation %g reaches %g degrees; the spiral must "
                  "stay below 90 (straight above the origin the camera has no up direction)",
                  orbit.elevation_deg, spiral.elevation_amplitude_deg, highest);
    return text;
  }
  return "";
}

trainer::Camera OrbitView(int width, int height, const OrbitPose& pose) {
  const dec::Camera d = dec::OrbitCameraDegrees(width, height, pose.azimuth_deg, pose.elevation_deg,
                                                float(pose.radius));
  trainer::Camera c;
  c.width = width;
  c.height = height;
  c.fx = d.fx;
  c.fy = d.fy;
  c.cx = d.cx;
  c.cy = d.cy;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 4; ++k) c.c2w[r][k] = d.c2w[r * 4 + k];
  }
  return c;
}

std::vector<PathCamera> OrbitPath(int frames, const OrbitShape& orbit) {
  std::vector<PathCamera> path;
  for (int k = 0; k < frames; ++k) {
    path.push_back({FrameName("orbit", k),
                    OrbitView(orbit.width, orbit.height, OrbitPoseAt(k, frames, orbit))});
  }
  return path;
}

std::vector<PathCamera> SpiralPath(int frames, const OrbitShape& orbit, const SpiralShape& spiral) {
  std::vector<PathCamera> path;
  for (int k = 0; k < frames; ++k) {
    path.push_back({FrameName("spiral", k),
                    OrbitView(orbit.width, orbit.height, SpiralPoseAt(k, frames, orbit, spiral))});
  }
  return path;
}

}  // namespace tools
}  // namespace ecrf
