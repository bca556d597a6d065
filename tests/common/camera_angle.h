// Camera orientations for the camera refinement tests: how far a refined camera is turned from
// the truth.
#ifndef ECRF_TESTS_COMMON_CAMERA_ANGLE_H_
#define ECRF_TESTS_COMMON_CAMERA_ANGLE_H_

#include <Eigen/Geometry>
#include <cmath>

#include "trainer/data/camera.h"

namespace ecrf {
namespace testing_camera {

inline Eigen::Matrix3d RotationOf(const trainer::Camera& c) {
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = c.c2w[i][j];
  return r;
}

// The angle between two cameras' orientations, in degrees.
inline double AngleDeg(const trainer::Camera& a, const trainer::Camera& b) {
  return Eigen::AngleAxisd(RotationOf(a).transpose() * RotationOf(b)).angle() * 180.0 / M_PI;
}

}  // namespace testing_camera
}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_CAMERA_ANGLE_H_
