#include "trainer/data/ray_set.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <string>

#include "trainer/data/camera.h"

namespace ecrf {
namespace trainer {

RaySet::RaySet(const std::vector<View>& views) : views_(views) {
  view_offset_.push_back(0);
  for (const View& v : views) {
    if (v.rgb.channels != 3)
      throw std::invalid_argument("RaySet: view '" + v.name + "' is not RGB");
    view_offset_.push_back(view_offset_.back() + uint64_t(v.rgb.width) * v.rgb.height);
  }
  if (view_offset_.back() > UINT32_MAX) {
    throw std::invalid_argument("RaySet: more than 2^32 training pixels; use --downscale");
  }
  active_.resize(view_offset_.back());
  for (size_t i = 0; i < active_.size(); ++i) active_[i] = uint32_t(i);
}

void RaySet::UseCameras(const std::vector<Camera>* cameras) {
  if (cameras && cameras->size() != views_.size())
    throw std::invalid_argument("RaySet::UseCameras: one camera per view is needed");
  cameras_ = cameras;
}

void RaySet::Sample(int n, std::mt19937_64& rng, float* origins, float* dirs, float* rgb,
                    uint32_t* views_or_null) const {
  if (active_.empty()) throw std::runtime_error("RaySet::Sample: no rays are kept");
  std::uniform_int_distribution<size_t> pick(0, active_.size() - 1);
  for (int i = 0; i < n; ++i) {
    const uint32_t index = active_[pick(rng)];
    const uint32_t view = ViewOf(index);
    RayInView(view, index, origins + 3 * size_t(i), dirs + 3 * size_t(i), rgb + 3 * size_t(i));
    if (views_or_null) views_or_null[i] = view;
  }
}

uint32_t RaySet::ViewOf(uint32_t index) const {
  return uint32_t(std::upper_bound(view_offset_.begin(), view_offset_.end(), uint64_t(index)) -
                  view_offset_.begin()) -
         1;
}

void RaySet::Ray(uint32_t index, float origin[3], float dir[3], float rgb[3]) const {
  RayInView(ViewOf(index), index, origin, dir, rgb);
}

void RaySet::RayInView(size_t v, uint32_t index, float origin[3], float dir[3],
                       float rgb[3]) const {
  const View& view = views_[v];
  const uint32_t pixel = uint32_t(index - view_offset_[v]);
  const int x = int(pixel % uint32_t(view.rgb.width));
  const int y = int(pixel / uint32_t(view.rgb.width));
  GenerateRay(cameras_ ? (*cameras_)[v] : view.camera, x, y, origin, dir);
  for (int c = 0; c < 3; ++c) rgb[c] = view.rgb.at(x, y, c);
}

void RaySet::KeepFlagged(const std::vector<uint8_t>& flags) {
  size_t w = 0;
  for (size_t i = 0; i < active_.size(); ++i) {
    if (flags[i]) active_[w++] = active_[i];
  }
  active_.resize(w);
  active_.shrink_to_fit();
  order_.clear();  // the sampler starts a fresh permutation of the kept rays
  shuffle_rng_.clear();
  cursor_ = 0;
}

void RaySet::Filter(const std::function<bool(const float*, const float*)>& keep) {
  std::vector<uint8_t> flags(active_.size());
#pragma omp parallel for schedule(dynamic, 4096)
  for (long i = 0; i < long(active_.size()); ++i) {
    float o[3], d[3], c[3];
    Ray(active_[i], o, d, c);
    flags[i] = keep(o, d) ? 1 : 0;
  }
  KeepFlagged(flags);
}

bool RaySet::FilterChunked(
    const std::function<void(int, const float*, const float*, uint8_t*)>& keep, size_t min_keep) {
  const size_t chunk = 1 << 16;
  std::vector<float> o(chunk * 3), d(chunk * 3);
  std::vector<uint8_t> flags(active_.size());
  for (size_t begin = 0; begin < active_.size(); begin += chunk) {
    const int n = int(std::min(chunk, active_.size() - begin));
#pragma omp parallel for schedule(static)
    for (int i = 0; i < n; ++i) {
      float c[3];
      Ray(active_[begin + i], &o[3 * size_t(i)], &d[3 * size_t(i)], c);
    }
    keep(n, o.data(), d.data(), &flags[begin]);
  }
  size_t kept = 0;
  for (uint8_t f : flags) kept += f != 0;
  if (kept < min_keep) return false;
  KeepFlagged(flags);
  return true;
}

void RaySet::Shuffle(std::mt19937_64& rng) {
  std::ostringstream state;
  state << rng;
  shuffle_rng_ = state.str();
  order_ = active_;
  std::shuffle(order_.begin(), order_.end(), rng);
  cursor_ = 0;
}

void RaySet::NextBatch(int n, std::mt19937_64& rng, float* origins, float* dirs, float* rgb,
                       uint32_t* views_or_null) {
  if (active_.empty()) throw std::runtime_error("no training rays left (all were filtered out)");
  for (int i = 0; i < n; ++i) {
    if (order_.empty() || cursor_ >= order_.size()) Shuffle(rng);
    const uint32_t index = order_[cursor_++];
    const uint32_t v = ViewOf(index);  // one search per ray, for the ray and its view
    RayInView(v, index, origins + 3 * i, dirs + 3 * i, rgb + 3 * i);
    if (views_or_null) views_or_null[i] = v;
  }
}

void RaySet::SaveState(std::vector<float>* keep, std::string* shuffle_rng, uint64_t* cursor) const {
  keep->assign((total() + 15) / 16, 0.f);
  std::vector<uint32_t> bits(keep->size(), 0);
  for (uint32_t index : active_) bits[index / 16] |= 1u << (index % 16);
  for (size_t i = 0; i < bits.size(); ++i) (*keep)[i] = float(bits[i]);  // < 2^16: exact
  *shuffle_rng = order_.empty() ? std::string() : shuffle_rng_;
  *cursor = cursor_;
}

void RaySet::RestoreState(const std::vector<float>& keep, const std::string& shuffle_rng,
                          uint64_t cursor) {
  if (keep.size() != (total() + 15) / 16) {
    throw std::runtime_error("training state: the kept-ray set is for " +
                             std::to_string(16 * keep.size()) + " rays, these views have " +
                             std::to_string(total()));
  }
  active_.clear();
  for (size_t i = 0; i < keep.size(); ++i) {
    const float v = keep[i];
    if (!(v >= 0.f && v < 65536.f) || v != float(uint32_t(v)))
      throw std::runtime_error("training state: damaged ray set");
    const uint32_t bits = uint32_t(v);
    for (uint32_t b = 0; b < 16; ++b) {
      if (bits >> b & 1u) active_.push_back(uint32_t(16 * i + b));
    }
  }
  if (!active_.empty() && active_.back() >= total())
    throw std::runtime_error("training state: damaged ray set");
  order_.clear();
  shuffle_rng_.clear();
  cursor_ = 0;
  if (!shuffle_rng.empty()) {
    std::mt19937_64 rng;
    std::istringstream in(shuffle_rng);
    in >> rng;
    if (in.fail()) throw std::runtime_error("training state: damaged sampler state");
    Shuffle(rng);
    if (cursor > order_.size())
      throw std::runtime_error("training state: sampler position past its permutation");
    cursor_ = size_t(cursor);
  }
}

}  // namespace trainer
}  // namespace ecrf
