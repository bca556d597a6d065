#include "trainer/data/camera.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace ecrf::trainer {

std::string PoseProblem(const double c2w[3][4]) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      if (!std::isfinite(c2w[r][c])) return "the pose has a non-finite entry";
    }
  }
  // A degenerate rotation gives rays of NaN or zero direction, which train a NaN model; a
  // scaled one stretches every ray.
  double worst = 0.0;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      double dot = 0.0;
      for (int r = 0; r < 3; ++r) dot += c2w[r][a] * c2w[r][b];
      worst = std::max(worst, std::abs(dot - (a == b ? 1.0 : 0.0)));
    }
  }
  char text[160];
  if (!(worst <= kRotationTolerance)) {
    std::snprintf(text, sizeof(text),
                  "the rotation is not orthonormal (|R^T R - I| reaches %.3g, tolerance %g)", worst,
                  kRotationTolerance);
    return text;
  }
  const double det = c2w[0][0] * (c2w[1][1] * c2w[2][2] - c2w[1][2] * c2w[2][1]) -
                     c2w[0][1] * (c2w[1][0] * c2w[2][2] - c2w[1][2] * c2w[2][0]) +
                     c2w[0][2] * (c2w[1][0] * c2w[2][1] - c2w[1][1] * c2w[2][0]);
  if (!(det > 0.0)) return "the rotation is a reflection (det < 0)";
  const double distance = std::hypot(c2w[0][3], c2w[1][3], c2w[2][3]);  // no overflow
  if (!(distance <= kMaxCameraDistance)) {
    std::snprintf(text, sizeof(text),
                  "the camera position is %.3g from the origin, beyond %g scene units (rays are "
                  "traced in single precision)",
                  distance, kMaxCameraDistance);
    return text;
  }
  return "";
}

std::string IntrinsicsProblem(const Camera& camera) {
  char text[200];
  if (camera.width <= 0 || camera.height <= 0) {
    std::snprintf(text, sizeof(text), "the image size %dx%d is not positive", camera.width,
                  camera.height);
    return text;
  }
  const double pi = 3.14159265358979323846;
  const struct {
    const char* axis;
    double focal, extent;
  } axes[2] = {{"horizontal", camera.fx, double(camera.width)},
               {"vertical", camera.fy, double(camera.height)}};
  for (const auto& a : axes) {
    const double degrees = 2.0 * std::atan(0.5 * a.extent / a.focal) * 180.0 / pi;
    if (!(a.focal > 0.0 && std::isfinite(a.focal) && degrees >= kMinFieldOfViewDegrees &&
          degrees <= kMaxFieldOfViewDegrees)) {
      std::snprintf(text, sizeof(text),
                    "the focal length %g px gives a %s field of view of %.4g degrees over %g px "
                    "(need %g to %g)",
                    a.focal, a.axis, a.focal > 0.0 ? degrees : 180.0, a.extent,
                    kMinFieldOfViewDegrees, kMaxFieldOfViewDegrees);
      return text;
    }
  }
  if (!(camera.cx >= -camera.width && camera.cx <= 2.0 * camera.width &&
        camera.cy >= -camera.height && camera.cy <= 2.0 * camera.height)) {
    std::snprintf(text, sizeof(text),
                  "the principal point (%g, %g) lies more than an image size outside the %dx%d "
                  "image",
                  camera.cx, camera.cy, camera.width, camera.height);
    return text;
  }
  const double distortion[4] = {camera.k1, camera.k2, camera.p1, camera.p2};
  const char* names[4] = {"k1", "k2", "p1", "p2"};
  for (int k = 0; k < 4; ++k) {
    if (!(std::abs(distortion[k]) <= kMaxDistortion)) {
      std::snprintf(text, sizeof(text),
                    "the distortion coefficient %s = %g is not a lens (|%s| <= %g)", names[k],
                    distortion[k], names[k], kMaxDistortion);
      return text;
    }
  }
  return "";
}

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
