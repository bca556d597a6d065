// Cameras (SPEC.md 7.1): the pinhole model every render starts from, and the reference tools'
// orbit camera (informative): at `radius` from the origin, looking at it, +z up, a Blender-like
// field of view (0.6911 rad). The one C++ orbit, used by `ecrf render --orbit`, the Python
// module's orbit_camera and the conformance cameras; the web viewer repeats it in JavaScript
// (web/camera_controls.js). Binary32 with the C library's sin/cos/tan and no fused multiply-add
// (a decoder source), so that the same angles give the same camera bit for bit.
#ifndef ECRF_DECODER_CAMERA_H_
#define ECRF_DECODER_CAMERA_H_

namespace ecrf {
namespace dec {

// Pinhole camera. c2w: 3x4 row-major camera-to-world (OpenGL: the camera looks down -z, +y up).
// Pixel (i, j) (column i, row j from the top) has direction
// c2w[:3,:3] * ((i + 0.5 - cx) / fx, -(j + 0.5 - cy) / fy, -1), normalized; origin c2w[:,3].
struct Camera {
  float c2w[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  float fx = 1.f, fy = 1.f, cx = 0.f, cy = 0.f;
  int width = 0, height = 0;
};

void CameraRay(const Camera& camera, int i, int j, float origin[3], float dir[3]);

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

#endif  // ECRF_DECODER_CAMERA_H_
