#include "trainer/scene_fit.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace ecrf::trainer {
namespace {

constexpr int kLattice = 64;

// Whether the camera's image holds world point p.
bool Sees(const Camera& cam, const double p[3]) {
  double v[3];
  for (int a = 0; a < 3; ++a) {
    v[a] = 0;
    for (int k = 0; k < 3; ++k) v[a] += cam.c2w[k][a] * (p[k] - cam.c2w[k][3]);
  }
  if (!(v[2] < 0)) return false;  // behind the camera (it looks down -z)
  const double x = v[0] / -v[2], y = -v[1] / -v[2];
  // Far outside the image the distortion polynomial folds back: reject before applying it.
  const double half_x = std::max(cam.cx, cam.width - cam.cx) / cam.fx;
  const double half_y = std::max(cam.cy, cam.height - cam.cy) / cam.fy;
  if (std::fabs(x) > 2 * half_x || std::fabs(y) > 2 * half_y) return false;
  double xd = x, yd = y;
  if (cam.HasDistortion()) DistortNormalized(cam, x, y, &xd, &yd);
  const double u = cam.fx * xd + cam.cx, w = cam.fy * yd + cam.cy;
  return u >= 0 && u <= cam.width && w >= 0 && w <= cam.height;
}

double Volume(const double lo[3], const double hi[3]) {
  return (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
}

}  // namespace

Aabb FitRegionOfInterest(const std::vector<Camera>& cameras, const double box[2][3]) {
  Aabb out;
  for (int a = 0; a < 3; ++a) {
    out.min[a] = float(box[0][a]);
    out.max[a] = float(box[1][a]);
  }
  if (cameras.empty()) return out;
  const int needed = std::max(1, int(std::ceil(kRoiViewShare * double(cameras.size()))));
  double unit[3];
  for (int a = 0; a < 3; ++a) unit[a] = (box[1][a] - box[0][a]) / (kLattice - 1);
  // Per lattice slab k: whether each point qualifies (slabs in parallel, combined in order).
  std::vector<uint8_t> seen_by_enough(size_t(kLattice) * kLattice * kLattice, 0);
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < kLattice; ++k) {
    for (int j = 0; j < kLattice; ++j) {
      for (int i = 0; i < kLattice; ++i) {
        const double p[3] = {box[0][0] + unit[0] * i, box[0][1] + unit[1] * j, box[0][2] + unit[2] * k};
        int seen = 0;
        for (const Camera& cam : cameras) seen += Sees(cam, p) ? 1 : 0;
        seen_by_enough[(size_t(k) * kLattice + j) * kLattice + i] = seen >= needed;
      }
    }
  }
  int lo[3] = {kLattice, kLattice, kLattice}, hi[3] = {-1, -1, -1};
  long qualified = 0;
  for (int k = 0; k < kLattice; ++k) {
    for (int j = 0; j < kLattice; ++j) {
      for (int i = 0; i < kLattice; ++i) {
        if (!seen_by_enough[(size_t(k) * kLattice + j) * kLattice + i]) continue;
        ++qualified;
        const int idx[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          lo[a] = std::min(lo[a], idx[a]);
          hi[a] = std::max(hi[a], idx[a]);
        }
      }
    }
  }
  if (qualified < 8) return out;
  for (int a = 0; a < 3; ++a) {
    // A margin of kRoiMargin of the extent and one lattice step: what stands where the views
    // meet often reaches a little beyond (the top of an object seen from slightly above).
    const double lo_p = box[0][a] + unit[a] * lo[a], hi_p = box[0][a] + unit[a] * hi[a];
    const double margin = kRoiMargin * (hi_p - lo_p) + unit[a];
    out.min[a] = float(std::max(box[0][a], lo_p - margin));
    out.max[a] = float(std::min(box[1][a], hi_p + margin));
  }
  return out;
}

bool CamerasFaceOneWay(const std::vector<Camera>& cameras) {
  if (cameras.empty()) return false;
  double mean[3] = {0, 0, 0};
  for (const Camera& c : cameras) {
    for (int a = 0; a < 3; ++a) mean[a] -= c.c2w[a][2];  // viewing direction: -z column
  }
  const double len = std::sqrt(mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]);
  if (!(len > 0)) return false;
  const double cos_limit = std::cos(35.0 * M_PI / 180.0);
  for (const Camera& c : cameras) {
    double dot = 0, n = 0;
    for (int a = 0; a < 3; ++a) {
      dot -= c.c2w[a][2] * mean[a] / len;
      n += c.c2w[a][2] * c.c2w[a][2];
    }
    if (!(dot >= cos_limit * std::sqrt(n))) return false;
  }
  return true;
}

SceneFit FitScene(const std::string& scene_type, const Dataset& data) {
  if (scene_type != "auto" && scene_type != "object" && scene_type != "unbounded") {
    if (scene_type == "forward") {
      throw std::invalid_argument(
          "--scene-type forward: the NDC model for forward-facing captures is not implemented yet; "
          "use --scene-type unbounded (the contraction also covers forward-facing captures)");
    }
    throw std::invalid_argument("--scene-type: unknown scene type '" + scene_type +
                                "' (auto, object or unbounded)");
  }
  std::vector<Camera> cameras;
  cameras.reserve(data.views.size());
  for (const View& v : data.views) cameras.push_back(v.camera);
  SceneFit fit;
  fit.roi = FitRegionOfInterest(cameras, data.scene_aabb);
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = fit.roi.min[a], hi[a] = fit.roi.max[a];
  fit.roi_share = Volume(lo, hi) / Volume(data.scene_aabb[0], data.scene_aabb[1]);
  fit.forward_facing = CamerasFaceOneWay(cameras);
  if (scene_type == "object") {
    fit.model = SceneModel::kObject;
    fit.reason = "--scene-type object";
  } else if (scene_type == "unbounded") {
    fit.model = SceneModel::kUnbounded;
    fit.reason = "--scene-type unbounded";
  } else if (data.white_background) {
    fit.model = SceneModel::kObject;
    fit.reason = "white background: an object dataset";
  } else if (fit.roi_share >= kObjectRoiShare) {
    fit.model = SceneModel::kObject;
    fit.reason = "the views fill the dataset box";
  } else {
    fit.model = SceneModel::kUnbounded;
    fit.reason = fit.forward_facing ? "forward-facing cameras (no NDC model yet: contracted instead)"
                                    : "the views meet in a small part of the dataset box";
  }
  return fit;
}

}  // namespace ecrf::trainer
