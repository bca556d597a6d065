// Pinhole cameras with optional OpenCV lens distortion, and the rays they shoot.
#ifndef ECRF_TRAINER_DATA_CAMERA_H_
#define ECRF_TRAINER_DATA_CAMERA_H_

#include <string>
#include <vector>

namespace ecrf::trainer {

// Intrinsics in pixels for an image of width x height; (0, 0) is the top-left corner of the
// top-left pixel, so a pixel (i, j) has its centre at (i + 0.5, j + 0.5).
// k1 k2 p1 p2 are OpenCV's radial-tangential coefficients on normalised image coordinates
// (x right, y down), as Instant-NGP and nerfstudio store them.
// c2w is camera-to-world in the OpenGL/NeRF convention: the camera looks down its -z axis
// with +y up and +x right; column 3 is the camera centre in world space.
struct Camera {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0;
  double c2w[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};

  bool HasDistortion() const { return k1 != 0 || k2 != 0 || p1 != 0 || p2 != 0; }
};

// What every dataset loader checks before training (Blender, Instant-NGP and LLFF alike): each
// returns "" for a camera that can be trained on, else the problem with its value, for the
// loader to prefix with the file and the frame.
// Largest |R^T R - I| entry accepted for a camera rotation: poses written with 6 or more
// significant digits (COLMAP, Blender, nerfstudio) are orthonormal far within it.
inline constexpr double kRotationTolerance = 1e-3;
// Camera positions farther than this from the origin (scene units) are refused: rays are traced
// in binary32, which at 1e6 keeps 0.06 units of precision and at 1e300 none (#60).
inline constexpr double kMaxCameraDistance = 1e6;
// A pinhole camera's field of view on either axis, in degrees (camera_angle_x = pi, or a focal
// length of 1e-300, leaves no ray inside the scene).
inline constexpr double kMinFieldOfViewDegrees = 0.1, kMaxFieldOfViewDegrees = 175.0;
// |k1| |k2| |p1| |p2| above this are not a lens (real ones stay well below 1).
inline constexpr double kMaxDistortion = 10.0;
// The rotation orthonormal within kRotationTolerance and proper (det > 0), the translation finite
// and within kMaxCameraDistance of the origin.
std::string PoseProblem(const double c2w[3][4]);
// A positive size, the field of view within [kMinFieldOfViewDegrees, kMaxFieldOfViewDegrees] on
// both axes, the principal point within one image size of the image, finite distortion of at
// most kMaxDistortion.
std::string IntrinsicsProblem(const Camera& camera);

// Focal length in pixels for a horizontal (or vertical) field of view in radians spanning
// `extent` pixels, as NeRF's camera_angle_x defines it.
double FocalFromFieldOfView(double extent_pixels, double field_of_view);

// World-space ray through pixel (px, py) of the camera, sampled at the pixel centre: px = i
// hits pixel i's centre, px = i - 0.25 a quarter pixel left of it (for supersampling).
// `dir` has unit length, as TensoRF's ray directions do; `origin` is the camera centre.
void GenerateRay(const Camera& camera, double px, double py, float origin[3], float dir[3]);

// Rays of pixel rows [y0, y0 + rows), row-major: origins and dirs are resized to rows*width*3.
void GenerateRowRays(const Camera& camera, int y0, int rows, std::vector<float>* origins,
                     std::vector<float>* dirs);

// OpenCV distortion of an undistorted normalised image point (x right, y down, z = 1).
void DistortNormalized(const Camera& camera, double x, double y, double* xd, double* yd);

// Inverse of DistortNormalized by Newton's method; converges to ~1e-12 for the mild
// distortion of real lenses. Without distortion this is the identity.
void UndistortNormalized(const Camera& camera, double xd, double yd, double* x, double* y);

// The same camera for images downscaled with DownscaleArea(image, factor): intrinsics divide
// by factor and the size rounds down; distortion and pose are unchanged.
Camera ScaledCamera(const Camera& camera, int factor);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_DATA_CAMERA_H_
