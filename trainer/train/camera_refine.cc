#include "trainer/train/camera_refine.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

#include "trainer/data/camera.h"
#include "trainer/model/volume_render.h"

namespace ecrf {
namespace trainer {
namespace {

constexpr int kPose = 6;  // rotation (3, radians) then translation (3), in the camera frame
// The focal length (fx, with fy keeping its ratio to fx), cx, cy, k1, p1 and p2. k2 and the
// aspect stay: with them free, the rendered capture's refinement traded k1 against k2 and fy
// against cy, and drifted away from the true lens (docs/photos-to-dataset.md).
constexpr int kLens = 6;
using PoseMatrix = Eigen::Matrix<double, kPose, kPose>;
using LensMatrix = Eigen::Matrix<double, kLens, kLens>;
using PoseLens = Eigen::Matrix<double, kPose, kLens>;
using PoseVector = Eigen::Matrix<double, kPose, 1>;
using LensVector = Eigen::Matrix<double, kLens, 1>;

// The largest step, in units of the finite-difference steps (about half a pixel each): larger
// ones are scaled down to it. A trust region: while the field is still blurred by the cameras'
// errors, a full Gauss-Newton step fits the field's errors as much as the cameras' and moved the
// exact cameras of the rendered capture by degrees (docs/photos-to-dataset.md).
constexpr double kMaxStep = 4.0;

Eigen::Matrix3d Rotation(const Camera& c) {
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = c.c2w[i][j];
  return r;
}

Eigen::Vector3d Centre(const Camera& c) { return {c.c2w[0][3], c.c2w[1][3], c.c2w[2][3]}; }

void SetPose(const Eigen::Matrix3d& r, const Eigen::Vector3d& centre, Camera* c) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) c->c2w[i][j] = r(i, j);
    c->c2w[i][3] = centre[i];
  }
}

// The camera turned by omega (axis-angle, camera frame) about its centre and moved by tau (camera
// frame).
Camera MovedCamera(const Camera& c, const double* omega, const double* tau) {
  const Eigen::Vector3d w(omega[0], omega[1], omega[2]);
  const double angle = w.norm();
  const Eigen::Matrix3d turn = angle > 0 ? Eigen::AngleAxisd(angle, w / angle).toRotationMatrix()
                                         : Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d r = Rotation(c);
  Camera moved = c;
  SetPose(r * turn, Centre(c) + r * Eigen::Vector3d(tau[0], tau[1], tau[2]), &moved);
  return moved;
}

double LensValue(const Camera& c, int k) {
  const double v[kLens] = {c.fx, c.cx, c.cy, c.k1, c.p1, c.p2};
  return v[k];
}

void SetLensValue(Camera* c, int k, double value) {
  if (k == 0) {
    c->fy *= value / c->fx;
    c->fx = value;
  } else {
    double* v[kLens] = {&c->fx, &c->cx, &c->cy, &c->k1, &c->p1, &c->p2};
    *v[k] = value;
  }
}

// Finite-difference steps that move an image point by about half a pixel.
LensVector LensSteps(const Camera& c) {
  const double half_w = 0.5 * c.width, half_h = 0.5 * c.height;
  const double xe = half_w / c.fx, ye = half_h / c.fy;  // normalised edge coordinates
  const double r2 = xe * xe + ye * ye;
  LensVector h;
  h << 0.5 / std::max(xe, ye), 0.5, 0.5, 0.5 / (r2 * half_w), 0.5 / (r2 * half_w),
      0.5 / (r2 * half_w);
  return h;
}

// Distance from a camera to what it films, for the translation step.
double SceneDepth(const TensorfModel& model, const Camera& c) {
  const TensorfConfig& cfg = model.config();
  if (cfg.scene_model == SceneModel::kForward) {
    const float* a = cfg.ndc.world_to_ref;
    const double scale = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
    return 2.0 * cfg.ndc.near_plane / std::max(scale, 1e-12);
  }
  const Aabb& box = cfg.scene_model == SceneModel::kUnbounded ? cfg.roi : cfg.aabb;
  const Eigen::Vector3d centre(0.5 * (box.min[0] + box.max[0]), 0.5 * (box.min[1] + box.max[1]),
                               0.5 * (box.min[2] + box.max[2]));
  return std::max((Centre(c) - centre).norm(), 1e-6);
}

struct Pixel {
  int x, y;
};

// n of 4n random pixels of columns [0, columns), those with the largest luminance gradient
// (measured within those columns too).
std::vector<Pixel> ChoosePixels(const Image& im, int columns, int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> px(0, columns - 1), py(0, im.height - 1);
  auto lum = [&im, columns](int x, int y) {
    x = std::clamp(x, 0, columns - 1);
    y = std::clamp(y, 0, im.height - 1);
    return im.at(x, y, 0) + im.at(x, y, 1) + im.at(x, y, 2);
  };
  std::vector<std::pair<float, Pixel>> candidates;
  for (int i = 0; i < 4 * n; ++i) {
    const Pixel p{px(rng), py(rng)};
    const float gx = lum(p.x + 1, p.y) - lum(p.x - 1, p.y);
    const float gy = lum(p.x, p.y + 1) - lum(p.x, p.y - 1);
    candidates.push_back({gx * gx + gy * gy, p});
  }
  n = std::min(n, int(candidates.size()));
  std::nth_element(candidates.begin(), candidates.begin() + n, candidates.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<Pixel> chosen;
  for (int i = 0; i < n; ++i) chosen.push_back(candidates[size_t(i)].second);
  return chosen;
}

// Renders many (camera, view) jobs over each view's pixels in one batch and returns the
// residuals gain * render - image, 3 per pixel, job after job.
class ResidualRenderer {
 public:
  ResidualRenderer(const TensorfModel& model, const std::vector<const View*>& views,
                   const float* log_gain, const std::vector<std::vector<Pixel>>& pixels)
      : model_(model), views_(views), log_gain_(log_gain), pixels_(pixels) {}

  void Add(const Camera& camera, size_t view) { jobs_.push_back({camera, view}); }

  // Residuals of every job added since the last call, in order.
  std::vector<Eigen::VectorXd> Run() {
    size_t rays = 0;
    for (const Job& j : jobs_) rays += pixels_[j.view].size();
    std::vector<float> origins(3 * rays), dirs(3 * rays), rgb(3 * rays);
    size_t at = 0;
    for (const Job& j : jobs_) {
      for (const Pixel& p : pixels_[j.view]) {
        GenerateRay(j.camera, p.x, p.y, &origins[3 * at], &dirs[3 * at]);
        ++at;
      }
    }
    RenderRays(model_, int(rays), origins.data(), dirs.data(), rgb.data(), nullptr);
    std::vector<Eigen::VectorXd> out;
    at = 0;
    for (const Job& j : jobs_) {
      const std::vector<Pixel>& px = pixels_[j.view];
      Eigen::VectorXd r(3 * px.size());
      double gain[3] = {1.0, 1.0, 1.0};  // one exp per job and channel, not per pixel
      for (int c = 0; log_gain_ && c < 3; ++c)
        gain[c] = std::exp(double(log_gain_[3 * j.view + c]));
      for (size_t i = 0; i < px.size(); ++i, ++at) {
        for (int c = 0; c < 3; ++c) {
          // The clamp of TrainStep: a gain scales the pixel before it.
          const double shown = std::min(std::max(gain[c] * rgb[3 * at + c], 0.0), 1.0);
          r[3 * Eigen::Index(i) + c] = shown - views_[j.view]->rgb.at(px[i].x, px[i].y, c);
        }
      }
      out.push_back(std::move(r));
    }
    jobs_.clear();
    return out;
  }

 private:
  struct Job {
    Camera camera;
    size_t view;
  };
  const TensorfModel& model_;
  const std::vector<const View*>& views_;
  const float* log_gain_;
  const std::vector<std::vector<Pixel>>& pixels_;
  std::vector<Job> jobs_;
};

double MeanSquare(const std::vector<Eigen::VectorXd>& r) {
  double sum = 0;
  size_t n = 0;
  for (const Eigen::VectorXd& v : r) {
    sum += v.squaredNorm();
    n += size_t(v.size());
  }
  return n ? sum / double(n) : 0.0;
}

Camera WithLens(Camera c, const LensVector& lens) {
  for (int k = 0; k < kLens; ++k) SetLensValue(&c, k, lens[k]);
  return c;
}

LensVector LensOf(const Camera& c) {
  LensVector v;
  for (int k = 0; k < kLens; ++k) v[k] = LensValue(c, k);
  return v;
}

// Scales a step (in finite-difference units) down to kMaxStep.
template <typename Vector>
Vector Capped(const Vector& v) {
  const double m = v.cwiseAbs().maxCoeff();
  return m > kMaxStep ? Vector(v * (kMaxStep / m)) : v;
}

}  // namespace

bool SharedIntrinsics(const std::vector<Camera>& cameras) {
  if (cameras.empty()) return true;
  const Camera& f = cameras.front();
  for (const Camera& c : cameras) {
    if (c.width != f.width || c.height != f.height || c.fx != f.fx || c.fy != f.fy ||
        c.cx != f.cx || c.cy != f.cy || c.k1 != f.k1 || c.k2 != f.k2 || c.p1 != f.p1 ||
        c.p2 != f.p2)
      return false;
  }
  return true;
}

namespace {

// The finite-difference steps of each view's pose: half a pixel at the image centre (rotation)
// and at the scene's depth (translation).
std::vector<PoseVector> PoseSteps(const TensorfModel& model, const std::vector<Camera>& cameras) {
  std::vector<PoseVector> pose_step(cameras.size());
  for (size_t v = 0; v < cameras.size(); ++v) {
    const Camera& c = cameras[v];
    const double f = 0.5 * (c.fx + c.fy);
    const double rot = 0.5 / f, move = 0.5 * SceneDepth(model, c) / f;
    pose_step[v] << rot, rot, rot, move, move, move;
  }
  return pose_step;
}

// Queues the central differences: per view 2 x kPose pose jobs, then (lens) 2 x kLens lens jobs.
void AddDifferenceJobs(const std::vector<Camera>& cameras, const std::vector<PoseVector>& pose_step,
                       bool lens, const LensVector& lens_step, ResidualRenderer* render) {
  for (size_t v = 0; v < cameras.size(); ++v) {
    for (int k = 0; k < kPose; ++k) {
      for (double sign : {1.0, -1.0}) {
        double d[kPose] = {0, 0, 0, 0, 0, 0};
        d[k] = sign * pose_step[v][k];
        render->Add(MovedCamera(cameras[v], d, d + 3), v);
      }
    }
    if (!lens) continue;
    for (int k = 0; k < kLens; ++k) {
      for (double sign : {1.0, -1.0}) {
        Camera c = cameras[v];
        SetLensValue(&c, k, LensValue(c, k) + sign * lens_step[k]);
        render->Add(c, v);
      }
    }
  }
}

// The Gauss-Newton normal equations [H B; B^T C] d = -[g; gl] of the steps (in finite-difference
// units): per view the pose blocks H, g and B, shared by all views the lens blocks C and gl.
struct NormalEquations {
  std::vector<PoseMatrix> h;
  std::vector<PoseVector> g;
  std::vector<PoseLens> b;
  LensMatrix c = LensMatrix::Zero();
  LensVector gl = LensVector::Zero();
};

// The normal equations from the residuals and the residuals of the central differences (in the
// order of AddDifferenceJobs).
NormalEquations BuildNormalEquations(const std::vector<Eigen::VectorXd>& residual,
                                     const std::vector<Eigen::VectorXd>& moved, bool lens) {
  const size_t n_views = residual.size();
  const int per_view = 2 * kPose + (lens ? 2 * kLens : 0);
  NormalEquations eq;
  eq.h.resize(n_views);
  eq.g.resize(n_views);
  eq.b.resize(n_views);
  for (size_t v = 0; v < n_views; ++v) {
    const Eigen::Index rows = residual[v].size();
    Eigen::MatrixXd jp(rows, kPose), jl(rows, lens ? kLens : 0);
    const Eigen::VectorXd* r = &moved[v * size_t(per_view)];
    for (int k = 0; k < kPose; ++k) jp.col(k) = 0.5 * (r[2 * k] - r[2 * k + 1]);
    for (int k = 0; lens && k < kLens; ++k)
      jl.col(k) = 0.5 * (r[2 * kPose + 2 * k] - r[2 * kPose + 2 * k + 1]);
    eq.h[v] = jp.transpose() * jp;
    eq.g[v] = jp.transpose() * residual[v];
    if (lens) {
      eq.b[v] = jp.transpose() * jl;
      eq.c += jl.transpose() * jl;
      eq.gl += jl.transpose() * residual[v];
    }
  }
  return eq;
}

// The cameras after one Levenberg-Marquardt step with `damping`: the damped equations solved
// through the Schur complement of the per-view blocks, each step capped at kMaxStep.
std::vector<Camera> DampedStepCameras(const NormalEquations& eq, double damping, bool lens,
                                      const std::vector<PoseVector>& pose_step,
                                      const LensVector& lens_step,
                                      const std::vector<Camera>& cameras) {
  const size_t n_views = cameras.size();
  std::vector<PoseMatrix> h_inv(n_views);
  LensMatrix schur = eq.c;
  LensVector rhs = -eq.gl;
  for (size_t v = 0; v < n_views; ++v) {
    PoseMatrix damped = eq.h[v];
    damped.diagonal() += damping * eq.h[v].diagonal() + PoseVector::Constant(1e-9);
    h_inv[v] = damped.inverse();
    if (lens) {
      schur -= eq.b[v].transpose() * h_inv[v] * eq.b[v];
      rhs += eq.b[v].transpose() * h_inv[v] * eq.g[v];
    }
  }
  LensVector dl = LensVector::Zero();
  if (lens) {
    schur.diagonal() += damping * eq.c.diagonal() + LensVector::Constant(1e-9);
    dl = Capped<LensVector>(schur.ldlt().solve(rhs));
    if (!dl.allFinite()) dl.setZero();
  }
  const LensVector lens_now = LensOf(cameras.front()) + dl.cwiseProduct(lens_step);
  std::vector<Camera> trial(n_views);
  for (size_t v = 0; v < n_views; ++v) {
    PoseVector dp = h_inv[v] * (-eq.g[v] - (lens ? PoseVector(eq.b[v] * dl) : PoseVector::Zero()));
    if (!dp.allFinite()) dp.setZero();
    dp = Capped<PoseVector>(dp).cwiseProduct(pose_step[v]);
    trial[v] = MovedCamera(cameras[v], dp.data(), dp.data() + 3);
    if (lens) trial[v] = WithLens(trial[v], lens_now);
  }
  return trial;
}

// How far the cameras moved from start: the largest turn and the largest shift in pixels.
void MeasureMoves(const TensorfModel& model, const std::vector<Camera>& start,
                  const std::vector<Camera>& cameras, CameraRefineStats* stats) {
  for (size_t v = 0; v < cameras.size(); ++v) {
    const Camera& a = start[v];
    const Camera& z = cameras[v];
    const Eigen::AngleAxisd turn(Rotation(a).transpose() * Rotation(z));
    stats->max_rotation_deg = std::max(stats->max_rotation_deg, turn.angle() * 180.0 / M_PI);
    const double f = 0.5 * (a.fx + a.fy);
    const double shift =
        turn.angle() * f + (Centre(z) - Centre(a)).norm() * f / SceneDepth(model, a);
    stats->max_shift_px = std::max(stats->max_shift_px, shift);
  }
}

// RefineCameras on views given by pointer: the held-out alignment refines a subset of a dataset's
// views without copying their images.
CameraRefineStats RefineViewCameras(const TensorfModel& model,
                                    const std::vector<const View*>& views, const float* log_gain,
                                    const CameraRefineOptions& options,
                                    std::vector<Camera>* cameras) {
  if (cameras->size() != views.size())
    throw std::invalid_argument("RefineCameras: one camera per view is needed");
  CameraRefineStats stats;
  const size_t n_views = views.size();
  if (n_views == 0) return stats;
  std::vector<std::vector<Pixel>> pixels(n_views);
  for (size_t v = 0; v < n_views; ++v)
    pixels[v] =
        ChoosePixels(views[v]->rgb,
                     options.left_half ? std::max(1, views[v]->rgb.width / 2) : views[v]->rgb.width,
                     options.pixels_per_view, options.seed * 7919 + v);
  ResidualRenderer render(model, views, log_gain, pixels);
  const bool lens = options.intrinsics && n_views > 1 && SharedIntrinsics(*cameras);
  const std::vector<Camera> start = *cameras;
  const std::vector<PoseVector> pose_step = PoseSteps(model, *cameras);
  const LensVector lens_step = LensSteps(cameras->front());

  for (size_t v = 0; v < n_views; ++v) render.Add((*cameras)[v], v);
  std::vector<Eigen::VectorXd> residual = render.Run();
  stats.mse_before = stats.mse_after = MeanSquare(residual);
  double damping = 1e-2;
  for (int step = 0; step < options.steps; ++step) {
    AddDifferenceJobs(*cameras, pose_step, lens, lens_step, &render);
    const NormalEquations eq = BuildNormalEquations(residual, render.Run(), lens);
    // Levenberg-Marquardt: keep the damped step if the error falls, else damp more.
    bool accepted = false;
    for (int attempt = 0; attempt < 4 && !accepted; ++attempt) {
      std::vector<Camera> trial =
          DampedStepCameras(eq, damping, lens, pose_step, lens_step, *cameras);
      for (size_t v = 0; v < n_views; ++v) render.Add(trial[v], v);
      std::vector<Eigen::VectorXd> trial_residual = render.Run();
      const double mse = MeanSquare(trial_residual);
      if (mse < stats.mse_after) {
        *cameras = std::move(trial);
        residual = std::move(trial_residual);
        stats.mse_after = mse;
        ++stats.steps_taken;
        damping = std::max(damping / 3, 1e-6);
        accepted = true;
      } else {
        damping *= 8;
      }
    }
    if (!accepted) break;
  }
  MeasureMoves(model, start, *cameras, &stats);
  return stats;
}

}  // namespace

CameraRefineStats RefineCameras(const TensorfModel& model, const std::vector<View>& views,
                                const float* log_gain, const CameraRefineOptions& options,
                                std::vector<Camera>* cameras) {
  std::vector<const View*> pointers;
  for (const View& v : views) pointers.push_back(&v);
  return RefineViewCameras(model, pointers, log_gain, options, cameras);
}

std::vector<Camera> FollowRefinedCameras(const std::vector<Camera>& before,
                                         const std::vector<Camera>& after,
                                         const std::vector<Camera>& moved) {
  if (before.size() != after.size())
    throw std::invalid_argument("FollowRefinedCameras: camera lists of different sizes");
  std::vector<Camera> out = moved;
  if (before.size() < 3) return out;
  Eigen::Matrix3Xd from(3, Eigen::Index(before.size())), to(3, Eigen::Index(after.size()));
  for (size_t i = 0; i < before.size(); ++i) {
    from.col(Eigen::Index(i)) = Centre(before[i]);
    to.col(Eigen::Index(i)) = Centre(after[i]);
  }
  const Eigen::Matrix4d sim = Eigen::umeyama(from, to, true);
  const Eigen::Matrix3d sr = sim.topLeftCorner<3, 3>();
  const double scale = std::cbrt(sr.determinant());
  const Eigen::Matrix3d turn = sr / scale;
  const bool lens = SharedIntrinsics(after);
  for (Camera& c : out) {
    SetPose(turn * Rotation(c), sr * Centre(c) + sim.topRightCorner<3, 1>(), &c);
    if (lens) {
      // The held-out views may be scored at another size: the intrinsics scale with it.
      const double sx = c.fx / before.front().fx, sy = c.fy / before.front().fy;
      c = WithLens(c, LensOf(after.front()));  // the size stays the view's
      c.fy = after.front().fy;
      c.fx *= sx;
      c.cx *= sx;
      c.fy *= sy;
      c.cy *= sy;
    }
  }
  return out;
}

std::vector<Camera> AlignHeldOutCameras(const TensorfModel& model, const Dataset& train,
                                        const Dataset& test, const std::vector<Camera>& refined,
                                        const std::vector<size_t>& scored, uint64_t seed,
                                        std::vector<CameraRefineStats>* stats_or_null) {
  std::vector<Camera> before, held_out;
  for (const View& v : train.views) before.push_back(v.camera);
  for (const View& v : test.views) held_out.push_back(v.camera);
  held_out = FollowRefinedCameras(before, refined, held_out);
  // What the similarity leaves, each training camera's own correction, is local (it makes up for
  // the lens and for the matches near it): a held-out camera takes its nearest training
  // camera's.
  const std::vector<Camera> carried = FollowRefinedCameras(before, refined, before);
  for (Camera& h : held_out) {
    size_t nearest = 0;
    for (size_t v = 1; v < carried.size(); ++v) {
      if ((Centre(carried[v]) - Centre(h)).norm() < (Centre(carried[nearest]) - Centre(h)).norm())
        nearest = v;
    }
    const Eigen::Matrix3d turn =
        Rotation(refined[nearest]) * Rotation(carried[nearest]).transpose();
    SetPose(turn * Rotation(h), Centre(h) + Centre(refined[nearest]) - Centre(carried[nearest]),
            &h);
  }
  CameraRefineOptions o;
  o.pixels_per_view = 1024;  // few views: more pixels each, at little cost
  o.steps = 10;  // half of each view constrains its pose less: 6 steps left 0.3 deg of 1.3
  o.intrinsics = false;
  o.left_half = true;  // the half-image protocol: the right halves are scored
  o.seed = seed + 1000003;
  std::vector<const View*> views;
  std::vector<Camera> cameras;
  for (const size_t v : scored) {
    if (v >= test.views.size())
      throw std::invalid_argument("AlignHeldOutCameras: scored view out of range");
    views.push_back(&test.views[v]);
    cameras.push_back(held_out[v]);
  }
  const CameraRefineStats s = RefineViewCameras(model, views, nullptr, o, &cameras);
  for (size_t i = 0; i < scored.size(); ++i) held_out[scored[i]] = cameras[i];
  std::fprintf(
      stderr,
      "held-out cameras aligned to the field on the left halves of the %zu scored views of "
      "%zu (their right halves are scored): pixel error %.5f -> %.5f (%d steps), largest "
      "change %.3f deg, ~%.2f px\n",
      scored.size(), test.views.size(), s.mse_before, s.mse_after, s.steps_taken,
      s.max_rotation_deg, s.max_shift_px);
  if (stats_or_null) stats_or_null->push_back(s);
  return held_out;
}

Dataset WithCameras(Dataset data, const std::vector<Camera>& cameras) {
  if (cameras.empty()) return data;
  if (cameras.size() != data.views.size())
    throw std::invalid_argument("WithCameras: one camera per view is needed");
  for (size_t v = 0; v < cameras.size(); ++v) {
    data.views[v].camera = cameras[v];
    data.views[v].fitted_columns = data.views[v].rgb.width / 2;
  }
  return data;
}

}  // namespace trainer
}  // namespace ecrf
