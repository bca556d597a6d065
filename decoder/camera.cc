#include "decoder/camera.h"

#include <cmath>

namespace ecrf {
namespace dec {

void CameraRay(const Camera& camera, int i, int j, float origin[3], float dir[3]) {
  const float x = (static_cast<float>(i) + 0.5f - camera.cx) / camera.fx;
  const float y = -(static_cast<float>(j) + 0.5f - camera.cy) / camera.fy;
  const float z = -1.f;
  const float* m = camera.c2w;
  float d[3];
  for (int a = 0; a < 3; ++a) d[a] = m[4 * a] * x + m[4 * a + 1] * y + m[4 * a + 2] * z;
  const float inv = 1.f / std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  for (int a = 0; a < 3; ++a) {
    dir[a] = d[a] * inv;
    origin[a] = m[4 * a + 3];
  }
}

Camera OrbitCamera(int width, int height, float azimuth_rad, float elevation_rad, float radius) {
  Camera cam;
  const float pos[3] = {radius * std::cos(elevation_rad) * std::cos(azimuth_rad),
                        radius * std::cos(elevation_rad) * std::sin(azimuth_rad),
                        radius * std::sin(elevation_rad)};
  float z[3] = {pos[0] / radius, pos[1] / radius, pos[2] / radius};  // camera +z (backwards)
  const float up[3] = {0.f, 0.f, 1.f};
  float x[3] = {up[1] * z[2] - up[2] * z[1], up[2] * z[0] - up[0] * z[2],
                up[0] * z[1] - up[1] * z[0]};
  const float xn = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  for (float& v : x) v /= xn;
  const float y[3] = {z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2],
                      z[0] * x[1] - z[1] * x[0]};
  for (int a = 0; a < 3; ++a) {
    cam.c2w[4 * a + 0] = x[a];
    cam.c2w[4 * a + 1] = y[a];
    cam.c2w[4 * a + 2] = z[a];
    cam.c2w[4 * a + 3] = pos[a];
  }
  cam.width = width;
  cam.height = height;
  cam.fx = cam.fy = 0.5f * static_cast<float>(width) / std::tan(0.5f * 0.6911112070083618f);
  cam.cx = 0.5f * static_cast<float>(width);
  cam.cy = 0.5f * static_cast<float>(height);
  return cam;
}

float OrbitRadians(double degrees) {
  return static_cast<float>(degrees * 3.14159265358979323846 / 180.0);
}

Camera OrbitCameraDegrees(int width, int height, double azimuth_deg, double elevation_deg,
                          float radius) {
  return OrbitCamera(width, height, OrbitRadians(azimuth_deg), OrbitRadians(elevation_deg), radius);
}

}  // namespace dec
}  // namespace ecrf
