#include "trainer/data/camera.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace ecrf::trainer {

double FocalFromFieldOfView(double extent_pixels, double field_of_view) {
  return 0.5 * extent_pixels / std::tan(0.5 * field_of_view);
}

void DistortNormalized(const Camera& camera, double x, double y, double* xd, double* yd) {
  const double r2 = x * x + y * y;
  const double radial = 1.0 + camera.k1 * r2 + camera.k2 * r2 * r2;
  *xd = x * radial + 2.0 * camera.p1 * x * y + camera.p2 * (r2 + 2.0 * x * x);
  *yd = y * radial + camera.p1 * (r2 + 2.0 * y * y) + 2.0 * camera.p2 * x * y;
}

void UndistortNormalized(const Camera& camera, double xd, double yd, double* x_out, double* y_out) {
  double x = xd, y = yd;
  if (camera.HasDistortion()) {
    const double k1 = camera.k1, k2 = camera.k2, p1 = camera.p1, p2 = camera.p2;
    // Newton on f(x, y) = distort(x, y) - (xd, yd) with the analytic Jacobian; quadratic
    // convergence makes a handful of steps enough, the cap only guards pathological lenses.
    for (int iteration = 0; iteration < 50; ++iteration) {
      const double r2 = x * x + y * y;
      const double radial = 1.0 + k1 * r2 + k2 * r2 * r2;
      const double fx = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - xd;
      const double fy = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - yd;
      const double dradial = k1 + 2.0 * k2 * r2;  // d(radial)/d(r2)
      const double j00 = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
      const double j01 = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
      const double j10 = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
      const double j11 = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
      const double det = j00 * j11 - j01 * j10;
      if (std::abs(det) < 1e-15) break;
      const double step_x = (j11 * fx - j01 * fy) / det;
      const double step_y = (j00 * fy - j10 * fx) / det;
      x -= step_x;
      y -= step_y;
      if (std::abs(step_x) + std::abs(step_y) < 1e-14) break;
    }
  }
  *x_out = x;
  *y_out = y;
}

void GenerateRowRays(const Camera& camera, int y0, int rows, std::vector<float>* origins,
                     std::vector<float>* dirs) {
  const size_t n = static_cast<size_t>(rows) * camera.width;
  origins->resize(n * 3);
  dirs->resize(n * 3);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < camera.width; ++x) {
      const size_t i = static_cast<size_t>(y) * camera.width + x;
      GenerateRay(camera, x, y0 + y, &(*origins)[3 * i], &(*dirs)[3 * i]);
    }
  }
}

void GenerateRay(const Camera& camera, double px, double py, float origin[3], float dir[3]) {
  // Normalised coordinates in OpenCV orientation (y down), where the distortion model lives.
  double x = (px + 0.5 - camera.cx) / camera.fx;
  double y = (py + 0.5 - camera.cy) / camera.fy;
  UndistortNormalized(camera, x, y, &x, &y);
  // OpenGL camera space: y up, looking down -z.
  const double local[3] = {x, -y, -1.0};
  double world[3];
  for (int r = 0; r < 3; ++r) {
    world[r] =
        camera.c2w[r][0] * local[0] + camera.c2w[r][1] * local[1] + camera.c2w[r][2] * local[2];
  }
  const double inv_norm =
      1.0 / std::sqrt(world[0] * world[0] + world[1] * world[1] + world[2] * world[2]);
  for (int r = 0; r < 3; ++r) {
    dir[r] = static_cast<float>(world[r] * inv_norm);
    origin[r] = static_cast<float>(camera.c2w[r][3]);
  }
}

Camera ScaledCamera(const Camera& camera, int factor) {
  if (factor < 1)
    throw std::runtime_error("ScaledCamera: factor must be >= 1, got " + std::to_string(factor));
  Camera scaled = camera;
  scaled.width = camera.width / factor;
  scaled.height = camera.height / factor;
  scaled.fx = camera.fx / factor;
  scaled.fy = camera.fy / factor;
  scaled.cx = camera.cx / factor;
  scaled.cy = camera.cy / factor;
  return scaled;
}

}  // namespace ecrf::trainer
