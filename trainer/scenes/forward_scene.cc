#include "trainer/scenes/forward_scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "trainer/data/camera.h"
#include "trainer/scenes/capture_scene.h"
#include "trainer/scenes/procedural_math.h"

namespace ecrf::trainer {
namespace {

using procedural::Cross;
using procedural::Dot;
using procedural::kPi;
using procedural::Normalized;
using procedural::Random;
using procedural::Vec3;

constexpr double kDegree = kPi / 180.0;

Camera ForwardCamera(Vec3 position, Vec3 target, double roll, double pitch, double yaw, int width,
                     int height) {
  Camera camera;  // no distortion: LLFF's COLMAP step undistorts the photos
  camera.width = width;
  camera.height = height;
  camera.fx = FocalFromFieldOfView(width, kCaptureFieldOfView);
  camera.fy = camera.fx;
  camera.cx = width * (0.5 + kCaptureCxOffset);
  camera.cy = height * (0.5 + kCaptureCyOffset);
  procedural::LookAtPose(position, target, roll, pitch, yaw, camera.c2w);
  return camera;
}

// The whole sweep, whatever the split, so that train and test frames come from one capture and
// share their bounds.
std::vector<Camera> ForwardRig(int frames, int width, int height, uint32_t seed) {
  Random random(0xf0a4du ^ (uint64_t{seed} << 20));
  const Vec3 target{kForwardTarget[0], kForwardTarget[1], kForwardTarget[2]};
  const Vec3 back{0, -std::cos(kForwardElevation), std::sin(kForwardElevation)};  // towards the rig
  const Vec3 right{1, 0, 0};
  const Vec3 up = Cross(right, back * -1.0);  // the patch faces the still life
  const Vec3 centre = target + back * kForwardDistance;
  // Rows about as far apart as the frames within a row, so the patch is covered evenly.
  const double ideal_rows = std::sqrt(frames * kForwardPatchHeight / kForwardPatchWidth);
  const int rows = std::clamp(int(std::lround(ideal_rows)), 1, frames);
  std::vector<Camera> cameras;
  for (int r = 0; r < rows; ++r) {
    const int in_row = frames / rows + (r < frames % rows ? 1 : 0);
    for (int k = 0; k < in_row; ++k) {
      const int column =
          r % 2 ? in_row - 1 - k : k;  // back and forth: neighbouring frames are close
      const double u =
          ((column + 0.5) / in_row - 0.5 + 0.3 * random.Signed() / in_row) * kForwardPatchWidth;
      const double v =
          (0.5 - (r + 0.5) / rows + 0.3 * random.Signed() / rows) * kForwardPatchHeight;
      const Vec3 position = centre + right * u + up * v + back * (0.03 * random.Signed());
      const Vec3 aim = target + Vec3{random.Signed(), random.Signed(), random.Signed()} * 0.05;
      const double roll = 2 * kDegree * random.Signed();
      const double pitch = 1.5 * kDegree * random.Signed();
      const double yaw = 1.5 * kDegree * random.Signed();
      cameras.push_back(ForwardCamera(position, aim, roll, pitch, yaw, width, height));
    }
  }
  return cameras;
}

// The smallest and largest depth at which any pixel ray of the cameras meets a surface.
void DepthRange(const std::vector<Camera>& cameras, double* nearest, double* farthest) {
  double lo = INFINITY, hi = 0;
#pragma omp parallel for schedule(dynamic) reduction(min : lo) reduction(max : hi)
  for (int v = 0; v < int(cameras.size()); ++v) {
    const Camera& camera = cameras[v];
    const Vec3 axis{-camera.c2w[0][2], -camera.c2w[1][2], -camera.c2w[2][2]};
    for (int j = 0; j < camera.height; ++j) {
      for (int i = 0; i < camera.width; ++i) {
        float origin[3], dir[3];
        GenerateRay(camera, i, j, origin, dir);
        const double depth =
            CaptureSceneHitDistance(origin, dir) * Dot(Normalized({dir[0], dir[1], dir[2]}), axis);
        lo = std::min(lo, depth);
        hi = std::max(hi, depth);
      }
    }
  }
  *nearest = lo;
  *farthest = hi;
}

}  // namespace

Dataset MakeForwardScene(const std::string& split, int width, int height, int num_frames,
                         uint32_t seed) {
  procedural::CheckSceneArguments("forward", split, width, height);
  procedural::CheckFrameCount("forward", num_frames);
  const std::vector<Camera> cameras = ForwardRig(num_frames, width, height, seed);
  Dataset dataset;
  dataset.white_background = false;
  for (int a = 0; a < 3; ++a) {
    dataset.scene_aabb[0][a] = kCaptureRoomMin[a];
    dataset.scene_aabb[1][a] = kCaptureRoomMax[a];
  }
  double nearest, farthest;
  DepthRange(cameras, &nearest, &farthest);
  dataset.near = kForwardNearShare * nearest;
  dataset.far = farthest;
  dataset.views = RenderCaptureFrames("forward", cameras, split);
  return dataset;
}

}  // namespace ecrf::trainer
