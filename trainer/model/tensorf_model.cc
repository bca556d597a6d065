#include "trainer/model/tensorf_model.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "decoder/contraction.h"

namespace ecrf {
namespace trainer {
namespace {

// torch.linspace(0, 1, n) in float: the first half counts up from 0, the second half down from 1.
std::vector<float> Linspace01(int n) {
  std::vector<float> s(n);
  if (n == 1) {
    s[0] = 0.f;
    return s;
  }
  const float step = 1.f / static_cast<float>(n - 1);
  const int half = n / 2;
  for (int i = 0; i < n; ++i)
    s[i] = i < half ? step * static_cast<float>(i) : 1.f - step * static_cast<float>(n - 1 - i);
  return s;
}

void CheckRes(const std::array<int, 3>& res, const char* what) {
  for (int a = 0; a < 3; ++a)
    if (res[a] < 2)
      throw std::runtime_error(std::string(what) + ": every resolution must be >= 2, got " +
                               std::to_string(res[a]));
}

}  // namespace

int CalNSamples(const std::array<int, 3>& res, float step_ratio) {
  const double norm =
      std::sqrt(static_cast<double>(res[0]) * res[0] + static_cast<double>(res[1]) * res[1] +
                static_cast<double>(res[2]) * res[2]);
  return static_cast<int>(norm / step_ratio);
}

TensorfModel::TensorfModel(const TensorfConfig& config) : config_(config), head_(config.head) {
  if (config.head.num_products != config.app_ranks[0] + config.app_ranks[1] + config.app_ranks[2])
    throw std::runtime_error("TensorfConfig: head.num_products must equal the sum of app_ranks");
  aabb_ = config.aabb;
}

TensorfModel::TensorfModel(const TensorfModel& other)
    : config_(other.config_),
      aabb_(other.aabb_),
      res_(other.res_),
      units_(other.units_),
      inv_aabb_size_(other.inv_aabb_size_),
      step_size_(other.step_size_),
      n_samples_(other.n_samples_),
      density_(other.density_),
      appearance_(other.appearance_),
      head_(other.head_),
      mask_(other.mask_),
      has_mask_(other.has_mask_) {}

TensorfModel& TensorfModel::operator=(const TensorfModel& other) {
  if (this != &other) {
    TensorfModel copy(other);
    std::shared_ptr<void> ws = std::move(train_workspace);
    *this = std::move(copy);
    train_workspace = std::move(ws);
  }
  return *this;
}

void TensorfModel::UpdateStepSize() {
  for (int a = 0; a < 3; ++a) {
    const float size = aabb_.max[a] - aabb_.min[a];
    if (!(size > 0.f)) throw std::runtime_error("TensorfModel: empty aabb");
    inv_aabb_size_[a] = 2.0f / size;
    units_[a] = size / static_cast<float>(res_[a] - 1);
  }
  step_size_ = (units_[0] + units_[1] + units_[2]) / 3.f * config_.step_ratio;
}

void TensorfModel::Initialize(const std::array<int, 3>& res, uint64_t seed) {
  CheckRes(res, "TensorfModel::Initialize");
  aabb_ = config_.aabb;
  res_ = res;
  density_.Allocate(res, config_.density_ranks);
  appearance_.Allocate(res, config_.app_ranks);
  density_.InitNormal(config_.init_scale, seed * 3 + 1);
  appearance_.InitNormal(config_.init_scale, seed * 3 + 2);
  head_.Initialize(static_cast<uint32_t>(seed * 3 + 3));
  ClearAlphaMask();
  UpdateStepSize();
  n_samples_ = std::min(config_.max_samples, DefaultSamples());
}

int TensorfModel::DefaultSamples() const {
  if (!unbounded()) return CalNSamples(res_, config_.step_ratio);
  const double n = std::ceil(3.0 * 2.0 * kContractedExtent / step_size_) + 1;
  return n >= 1e6 ? 1000000 : static_cast<int>(n);
}

void TensorfModel::SetGeometry(const Aabb& aabb, const std::array<int, 3>& res) {
  CheckRes(res, "TensorfModel::SetGeometry");
  aabb_ = aabb;
  res_ = res;
  density_.Allocate(res, config_.density_ranks);
  appearance_.Allocate(res, config_.app_ranks);
  ClearAlphaMask();
  UpdateStepSize();
  if (n_samples_ == 0) n_samples_ = std::min(config_.max_samples, DefaultSamples());
}

void TensorfModel::SetStepRatio(float step_ratio) {
  if (!(step_ratio > 0.f) || !std::isfinite(step_ratio))
    throw std::invalid_argument("TensorfModel::SetStepRatio: step ratio must be positive");
  const double n = std::ceil(double(n_samples_) * config_.step_ratio / step_ratio);
  n_samples_ = static_cast<int>(std::max(1.0, std::min<double>(config_.max_samples, n)));
  config_.step_ratio = step_ratio;
  UpdateStepSize();
}

void TensorfModel::set_n_samples(int n) {
  if (n < 1) throw std::runtime_error("TensorfModel::set_n_samples: n must be >= 1");
  n_samples_ = n;
}

void TensorfModel::SetAlphaMask(AlphaMask mask) {
  mask_ = std::move(mask);
  has_mask_ = true;
}

void TensorfModel::UpsampleTo(const std::array<int, 3>& res) {
  CheckRes(res, "TensorfModel::UpsampleTo");
  density_.UpsampleTo(res);
  appearance_.UpsampleTo(res);
  res_ = res;
  UpdateStepSize();
  n_samples_ = std::min(config_.max_samples, DefaultSamples());
}

void TensorfModel::Normalize(const float xyz[3], float out[3]) const {
  for (int a = 0; a < 3; ++a) out[a] = (xyz[a] - aabb_.min[a]) * inv_aabb_size_[a] - 1.f;
}

float TensorfModel::Sigma(const float xyz[3]) const {
  float c[3];
  Normalize(xyz, c);
  GridPoint gp;
  LocateGridPoint(c, res_, &gp);
  return ActivateDensity(config_.density_activation, density_.Density(gp) + config_.density_shift);
}

Aabb TensorfModel::UpdateAlphaMask(const std::array<int, 3>& mask_res) {
  CheckRes(mask_res, "TensorfModel::UpdateAlphaMask");
  const int X = mask_res[0], Y = mask_res[1], Z = mask_res[2];
  std::array<std::vector<float>, 3> coord;
  for (int a = 0; a < 3; ++a) {
    const std::vector<float> s = Linspace01(mask_res[a]);
    coord[a].resize(s.size());
    for (size_t i = 0; i < s.size(); ++i)
      coord[a][i] = aabb_.min[a] * (1.f - s[i]) + aabb_.max[a] * s[i];
  }
  const size_t total = static_cast<size_t>(X) * Y * Z;
  std::vector<uint8_t> occ(total, 0);
  const AlphaMask* old_mask = alpha_mask();
  const float length = step_size_ * config_.alpha_mask_length_scale;
  const float thres = config_.alpha_mask_threshold;
  // Unbounded: step_size_ is a contracted length; a sample at contracted point x stands for about
  // step * (ROI half-size) * max_a q_a^2 world units (q = the uncontracted, normalised point), so
  // the background, sampled ever more sparsely, keeps what its long intervals make opaque.
  float roi_half = 0.f;
  for (int a = 0; a < 3; ++a) roi_half += (config_.roi.max[a] - config_.roi.min[a]) / 6.f;
  auto sample_length = [&](const float xyz[3]) {
    if (!unbounded()) return length;
    float stretch = 1.f;
    for (int a = 0; a < 3; ++a) {
      const float q = UncontractCoordinate(xyz[a]);
      stretch = std::max(stretch, q * q);
    }
    return length * roi_half * stretch;
  };
  const int64_t rows = static_cast<int64_t>(Y) * Z;
#pragma omp parallel for schedule(dynamic, 4) if (total > 65536)
  for (int64_t row = 0; row < rows; ++row) {
    const int y = static_cast<int>(row % Y), z = static_cast<int>(row / Y);
    uint8_t* out = occ.data() + static_cast<size_t>(row) * X;
    for (int x = 0; x < X; ++x) {
      const float xyz[3] = {coord[0][x], coord[1][y], coord[2][z]};
      if (old_mask && !old_mask->Occupied(xyz)) continue;  // alpha 0
      const float sigma = Sigma(xyz);
      const float alpha = 1.f - std::exp(-sigma * sample_length(xyz));
      out[x] = alpha >= thres ? 1 : 0;
    }
  }
  // 3x3x3 max-pool (stride 1, padding 1) of a 0/1 volume == dilation; separable per axis.
  std::vector<uint8_t> tmp(total);
  const size_t strides[3] = {1, static_cast<size_t>(X), static_cast<size_t>(X) * Y};
  for (int a = 0; a < 3; ++a) {
    const int n = mask_res[a];
    const size_t st = strides[a];
    const int64_t total64 = static_cast<int64_t>(total);
#pragma omp parallel for schedule(static) if (total64 > 65536)
    for (int64_t k = 0; k < total64; ++k) {
      const int i = static_cast<int>((static_cast<size_t>(k) / st) % n);
      uint8_t v = occ[k];
      if (i > 0) v |= occ[k - st];
      if (i + 1 < n) v |= occ[k + st];
      tmp[k] = v;
    }
    occ.swap(tmp);
  }
  // Bounding box of the occupied grid points.
  std::array<int, 3> lo{{X, Y, Z}}, hi{{-1, -1, -1}};
  for (int z = 0; z < Z; ++z)
    for (int y = 0; y < Y; ++y) {
      const uint8_t* r = occ.data() + (static_cast<size_t>(z) * Y + y) * X;
      int first = -1, last = -1;
      for (int x = 0; x < X; ++x)
        if (r[x]) {
          if (first < 0) first = x;
          last = x;
        }
      if (first < 0) continue;
      lo[0] = std::min(lo[0], first);
      hi[0] = std::max(hi[0], last);
      lo[1] = std::min(lo[1], y);
      hi[1] = std::max(hi[1], y);
      lo[2] = std::min(lo[2], z);
      hi[2] = std::max(hi[2], z);
    }
  SetAlphaMask(AlphaMask(aabb_, mask_res, std::move(occ)));
  if (hi[0] < 0) return aabb_;
  Aabb box;
  for (int a = 0; a < 3; ++a) {
    box.min[a] = coord[a][lo[a]];
    box.max[a] = coord[a][hi[a]];
  }
  return box;
}

bool TensorfModel::RefreshAlphaMask(int mask_downscale) {
  if (!has_mask_) return false;
  if (mask_downscale > 1) {
    UpdateAlphaMask(res_);
    SetAlphaMask(CoarsenAlphaMask(mask_, mask_downscale));
    return true;
  }
  // On the last update's points, which were the grid's before its last upsamplings: the OCCU
  // chunk costs what it did. At the grid's points the shell is thinner, for 1.6x its bytes
  // (chair: 8.3 samples a ray either way; 595,373 B against 606,328 B; docs/results.md).
  std::array<int, 3> res = mask_.res();
  for (int a = 0; a < 3; ++a) res[a] = std::min(res[a], res_[a]);
  UpdateAlphaMask(res);
  return true;
}

void TensorfModel::Shrink(const Aabb& new_aabb) {
  std::array<int, 3> tl, br;
  for (int a = 0; a < 3; ++a) {
    const float l = (new_aabb.min[a] - aabb_.min[a]) / units_[a];
    const float r = (new_aabb.max[a] - aabb_.min[a]) / units_[a];
    tl[a] = static_cast<int>(std::nearbyint(l));  // torch.round: half to even
    br[a] = static_cast<int>(std::nearbyint(r)) + 1;
    tl[a] = std::max(tl[a], 0);
    br[a] = std::min(br[a], res_[a]);
    if (br[a] - tl[a] < 2)
      throw std::runtime_error(
          "TensorfModel::Shrink: the new box keeps fewer than 2 vertices on axis " +
          std::to_string(a));
  }
  density_.Crop(tl, br);
  appearance_.Crop(tl, br);
  Aabb box = new_aabb;
  if (!has_mask_ || mask_.res() != res_) {
    for (int a = 0; a < 3; ++a) {
      const float tlr = static_cast<float>(tl[a]) / static_cast<float>(res_[a] - 1);
      const float brr = static_cast<float>(br[a] - 1) / static_cast<float>(res_[a] - 1);
      box.min[a] = (1.f - tlr) * aabb_.min[a] + tlr * aabb_.max[a];
      box.max[a] = (1.f - brr) * aabb_.min[a] + brr * aabb_.max[a];
    }
  }
  aabb_ = box;
  for (int a = 0; a < 3; ++a) res_[a] = br[a] - tl[a];
  UpdateStepSize();
}

std::vector<uint8_t> TensorfModel::FilterRays(int64_t n, const float* origins, const float* dirs,
                                              bool bbox_only, int n_samples) const {
  std::vector<uint8_t> keep(static_cast<size_t>(n), 0);
  const bool use_mask = !bbox_only && has_mask_;
  Aabb mask_box;
  if (use_mask) {
    mask_box = mask_.aabb();
    for (int a = 0; a < 3; ++a) {
      const float unit =
          (mask_box.max[a] - mask_box.min[a]) / static_cast<float>(mask_.res()[a] - 1);
      mask_box.min[a] -= 1.01f * unit;
      mask_box.max[a] += 1.01f * unit;
    }
  }
#pragma omp parallel for schedule(dynamic, 256) if (n > 1024)
  for (int64_t i = 0; i < n; ++i) {
    const float* o = origins + 3 * i;
    const float* d = dirs + 3 * i;
    float t_enter, t_exit;
    RayAabb(aabb_, o, d, &t_enter, &t_exit);
    if (!use_mask) {
      keep[i] = t_exit > t_enter ? 1 : 0;
      continue;
    }
    const float t_min = std::min(std::max(t_enter, config_.near), config_.far);
    // Samples farther than one mask voxel outside the mask's box always read 0: only the index
    // range crossing the expanded box is tested.
    float m_enter, m_exit;
    RayAabb(mask_box, o, d, &m_enter, &m_exit);
    if (!(m_exit >= m_enter)) continue;
    const double lo = std::floor((static_cast<double>(m_enter) - t_min) / step_size_) - 1;
    const double hi = std::ceil((static_cast<double>(m_exit) - t_min) / step_size_) + 2;
    const int s_lo = static_cast<int>(std::max(0.0, std::min(lo, static_cast<double>(n_samples))));
    const int s_hi = static_cast<int>(std::max(0.0, std::min(hi, static_cast<double>(n_samples))));
    uint8_t hit = 0;
    for (int s = s_lo; s < s_hi && !hit; ++s) {
      const float t = t_min + step_size_ * static_cast<float>(s);
      const float p[3] = {o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t};
      if (mask_.Occupied(p)) hit = 1;
    }
    keep[i] = hit;
  }
  return keep;
}

void TensorfModel::KeepComponents(int grid, const std::array<std::vector<uint8_t>, 3>& keep) {
  if (grid != 0 && grid != 1) throw std::invalid_argument("KeepComponents: grid 0 or 1");
  VmGrid& g = grid == 0 ? density_ : appearance_;
  if (grid == 1) {
    std::vector<uint8_t> products;
    for (int m = 0; m < 3; ++m) products.insert(products.end(), keep[m].begin(), keep[m].end());
    if (products.size() != static_cast<size_t>(head_.config().num_products)) {
      throw std::invalid_argument("KeepComponents: the head's inputs do not match the grid");
    }
    g.KeepComponents(keep);  // checks every mode keeps a component before the head changes
    head_.KeepProducts(products);
    config_.app_ranks = g.ranks();
    config_.head.num_products = head_.config().num_products;
  } else {
    g.KeepComponents(keep);
    config_.density_ranks = g.ranks();
  }
  train_workspace.reset();  // its buffers were sized for the old ranks
}

void TensorfModel::ReplaceHead(const AppearanceHeadConfig& head, uint32_t seed) {
  if (head.num_products != head_.config().num_products) {
    throw std::invalid_argument("ReplaceHead: the new head has other products than the grid");
  }
  head_ = AppearanceHead(head);
  head_.Initialize(seed);
  config_.head = head;
  train_workspace.reset();
}

void TensorfModel::KeepHidden(const std::vector<uint8_t>& keep1,
                              const std::vector<uint8_t>& keep2) {
  head_.KeepHidden(keep1, keep2);
  config_.head.hidden = head_.config().hidden;
  train_workspace.reset();
}

void TensorfModel::ZeroGrads() {
  density_.ZeroGrads();
  appearance_.ZeroGrads();
  head_.ZeroGrads();
}

double TensorfModel::DensityL1(float weight) { return density_.L1(weight); }

std::vector<NamedArray> TensorfModel::NamedParameters() {
  std::vector<NamedArray> out;
  const char* names[2] = {"density", "appearance"};
  VmGrid* grids[2] = {&density_, &appearance_};
  for (int g = 0; g < 2; ++g) {
    VmGrid& grid = *grids[g];
    for (int m = 0; m < 3; ++m) {
      NamedArray a;
      a.name = std::string(names[g]) + ".plane." + std::to_string(m);
      a.shape = {grid.res()[kMatMode[m][1]], grid.res()[kMatMode[m][0]], grid.ranks()[m]};
      a.data = grid.plane(m);
      a.grad = grid.plane_grad(m);
      a.size = grid.plane_size(m);
      out.push_back(a);
    }
    for (int m = 0; m < 3; ++m) {
      NamedArray a;
      a.name = std::string(names[g]) + ".line." + std::to_string(m);
      a.shape = {grid.res()[kVecMode[m]], grid.ranks()[m]};
      a.data = grid.line(m);
      a.grad = grid.line_grad(m);
      a.size = grid.line_size(m);
      out.push_back(a);
    }
  }
  NamedArray h;
  h.name = "head";
  h.shape = {static_cast<int64_t>(head_.params().size())};
  h.data = head_.params().data();
  h.grad = head_.grads().data();
  h.size = head_.params().size();
  out.push_back(h);
  return out;
}

}  // namespace trainer
}  // namespace ecrf
