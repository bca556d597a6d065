// The reference tools' orbit camera (SPEC.md 7.1, informative): at `radius` from the origin,
// looking at it, +z up, a Blender-like field of view (0.6911 rad). One C++ definition for
// `ecrf render --orbit`, the Python module's orbit_camera and the conformance cameras; the web
// viewer repeats it in JavaScript (web/camera_controls.js). Binary32 with the C library's
// sin/cos/tan and no fused multiply-add (a decoder source), so that the same angles give the same
// camera bit for bit.
#ifndef ECRF_DECODER_ORBIT_CAMERA_H_
#define ECRF_DECODER_ORBIT_CAMERA_H_

#include "decoder/ray_marcher.h"

namespace ecrf {
namespace dec {

Camera OrbitCamera(int width, int height, float azimuth_rad, float elevation_rad, float radius);

// Degrees, as the command line, the Python module and the web viewer take them, to radians: in
// float64, rounded once to float32 (web/camera_controls.js converts the same way).
float OrbitRadians(double degrees);

// OrbitCamera with angles in degrees: frame k of `ecrf render --orbit N` is
// OrbitCameraDegrees(W, H, 360.0 * k / N, elevation, radius).
Camera OrbitCameraDegrees(int width, int height, double azimuth_deg, double elevation_deg,
                          float radius);

}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_DECODER_ORBIT_CAMERA_H_
