#include "trainer/data/scene_fit.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "decoder/ndc.h"

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

namespace {

// The lattice bounds (lo, hi, in lattice steps of `box`) of the kLattice^3 points of `box` that
// `needed` cameras see; false when fewer than 8 qualify.
bool SeenLatticeBounds(const std::vector<Camera>& cameras, const double box[2][3], int needed,
                       int lo[3], int hi[3]) {
  double unit[3];
  for (int a = 0; a < 3; ++a) unit[a] = (box[1][a] - box[0][a]) / (kLattice - 1);
  // Per lattice slab k: whether each point qualifies (slabs in parallel, combined in order).
  std::vector<uint8_t> seen_by_enough(size_t(kLattice) * kLattice * kLattice, 0);
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < kLattice; ++k) {
    for (int j = 0; j < kLattice; ++j) {
      for (int i = 0; i < kLattice; ++i) {
        const double p[3] = {box[0][0] + unit[0] * i, box[0][1] + unit[1] * j,
                             box[0][2] + unit[2] * k};
        int seen = 0;
        for (const Camera& cam : cameras) seen += Sees(cam, p) ? 1 : 0;
        seen_by_enough[(size_t(k) * kLattice + j) * kLattice + i] = seen >= needed;
      }
    }
  }
  for (int a = 0; a < 3; ++a) lo[a] = kLattice, hi[a] = -1;
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
  return qualified >= 8;
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
  int lo[3], hi[3];
  if (!SeenLatticeBounds(cameras, box, needed, lo, hi)) return out;
  // Again on a lattice over the first one's box widened by one step: the fit then does not
  // depend on how large the dataset box is (Instant-NGP's aabb_scale 16 made one step of the
  // first lattice a quarter of the region, and the region 1.6x too large in volume on the
  // rendered capture, docs/photos-to-dataset.md).
  double fine[2][3], unit[3];
  for (int a = 0; a < 3; ++a) {
    const double step = (box[1][a] - box[0][a]) / (kLattice - 1);
    fine[0][a] = std::max(box[0][a], box[0][a] + step * (lo[a] - 1));
    fine[1][a] = std::min(box[1][a], box[0][a] + step * (hi[a] + 1));
  }
  int fine_lo[3], fine_hi[3];
  const bool refined = SeenLatticeBounds(cameras, fine, needed, fine_lo, fine_hi);
  const double(*fitted)[3] = refined ? fine : box;
  if (refined) {
    for (int a = 0; a < 3; ++a) lo[a] = fine_lo[a], hi[a] = fine_hi[a];
  }
  for (int a = 0; a < 3; ++a) unit[a] = (fitted[1][a] - fitted[0][a]) / (kLattice - 1);
  for (int a = 0; a < 3; ++a) {
    // A margin of kRoiMargin of the extent and one lattice step: what stands where the views
    // meet often reaches a little beyond (the top of an object seen from slightly above).
    const double lo_p = fitted[0][a] + unit[a] * lo[a], hi_p = fitted[0][a] + unit[a] * hi[a];
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

NdcFrame FitNdcFrame(const std::vector<Camera>& cameras, double near) {
  if (cameras.empty()) throw std::invalid_argument("forward-facing scene: no cameras");
  if (!(near > 0) || !std::isfinite(near)) {
    throw std::invalid_argument(
        "forward-facing scene: the dataset's near bound must be positive (got " +
        std::to_string(near) + ")");
  }
  double centre[3] = {0, 0, 0}, back[3] = {0, 0, 0}, up[3] = {0, 0, 0}, scale[2] = {0, 0};
  for (const Camera& c : cameras) {
    for (int a = 0; a < 3; ++a) {
      centre[a] += c.c2w[a][3] / cameras.size();
      back[a] += c.c2w[a][2];
      up[a] += c.c2w[a][1];
    }
    scale[0] += 2 * c.fx / c.width / cameras.size();
    scale[1] += 2 * c.fy / c.height / cameras.size();
  }
  auto normalise = [](double v[3]) {
    const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int a = 0; a < 3; ++a) v[a] /= len;
  };
  auto cross = [](const double a[3], const double b[3], double out[3]) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
  };
  double x[3], y[3];
  normalise(back);
  cross(up, back, x);
  normalise(x);
  cross(back, x, y);
  const double* axes[3] = {x, y, back};  // rows of the rotation world -> reference
  NdcFrame f;
  for (int r = 0; r < 3; ++r) {
    double offset = 0;
    for (int a = 0; a < 3; ++a) {
      f.world_to_ref[4 * r + a] = float(axes[r][a]);
      offset -= axes[r][a] * centre[a];
    }
    f.world_to_ref[4 * r + 3] = float(offset);
  }
  f.scale[0] = float(scale[0]);
  f.scale[1] = float(scale[1]);
  f.near_plane = float(kNdcNearShare * near);
  return f;
}

Aabb FitNdcBox(const std::vector<Camera>& cameras, const NdcFrame& frame) {
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (const Camera& c : cameras) {
    for (int corner = 0; corner < 4; ++corner) {
      const double px = (corner & 1) ? c.width - 0.5 : -0.5,
                   py = (corner & 2) ? c.height - 0.5 : -0.5;
      float o[3], d[3], ndc_o[3], ndc_d[3];
      GenerateRay(c, px, py, o, d);
      if (!NdcRay(frame, o, d, ndc_o, ndc_d)) continue;
      const double t_far = (1.0 - ndc_o[2]) / ndc_d[2];  // where the ray reaches z = 1
      for (int a = 0; a < 2; ++a) {
        for (double t : {0.0, t_far}) {
          const double v = ndc_o[a] + ndc_d[a] * t;
          lo[a] = std::min(lo[a], v);
          hi[a] = std::max(hi[a], v);
        }
      }
    }
  }
  if (!(hi[0] > lo[0] && hi[1] > lo[1])) {
    throw std::invalid_argument(
        "forward-facing scene: the cameras' corner rays never cross the reference near plane");
  }
  Aabb box;
  for (int a = 0; a < 2; ++a) {
    const double margin = kNdcBoxMargin * (hi[a] - lo[a]);
    box.min[a] = float(lo[a] - margin);
    box.max[a] = float(hi[a] + margin);
  }
  box.min[2] = -1.f;
  box.max[2] = 1.f;
  return box;
}

bool ModelsForwardFacing(SceneType scene_type, bool white_background,
                         const std::vector<Camera>& cameras) {
  return scene_type == SceneType::kForward ||
         (scene_type == SceneType::kAuto && !white_background && CamerasFaceOneWay(cameras));
}

SceneFit FitScene(SceneType scene_type, const Dataset& data) {
  std::vector<Camera> cameras;
  cameras.reserve(data.views.size());
  for (const View& v : data.views) cameras.push_back(v.camera);
  SceneFit fit;
  fit.roi = FitRegionOfInterest(cameras, data.scene_aabb);
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = fit.roi.min[a], hi[a] = fit.roi.max[a];
  fit.roi_share = Volume(lo, hi) / Volume(data.scene_aabb[0], data.scene_aabb[1]);
  fit.forward_facing = CamerasFaceOneWay(cameras);
  if (scene_type == SceneType::kObject) {
    fit.model = SceneModel::kObject;
    fit.reason = "--scene-type object";
  } else if (scene_type == SceneType::kUnbounded) {
    fit.model = SceneModel::kUnbounded;
    fit.reason = "--scene-type unbounded";
  } else if (ModelsForwardFacing(scene_type, data.white_background, cameras)) {
    fit.model = SceneModel::kForward;
    fit.reason = scene_type == SceneType::kForward
                     ? "--scene-type forward"
                     : "every camera looks within 35 degrees of their mean direction";
  } else if (data.white_background) {
    fit.model = SceneModel::kObject;
    fit.reason = "white background: an object dataset";
  } else if (fit.roi_share >= kObjectRoiShare) {
    fit.model = SceneModel::kObject;
    fit.reason = "the views fill the dataset box";
  } else {
    fit.model = SceneModel::kUnbounded;
    fit.reason = "the views meet in a small part of the dataset box";
  }
  if (fit.model == SceneModel::kForward) {
    fit.ndc = FitNdcFrame(cameras, data.near);
    fit.roi = FitNdcBox(cameras, fit.ndc);
    fit.roi_share = 1.0;  // an NDC box: not comparable with the dataset box
  }
  return fit;
}

}  // namespace ecrf::trainer
