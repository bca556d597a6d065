// The training rays of a set of views, made on demand from (view, pixel) indices so that 100
// views of 400x400 cost 4 bytes a ray instead of 36.
#ifndef ECRF_TRAINER_DATA_RAY_SET_H_
#define ECRF_TRAINER_DATA_RAY_SET_H_

#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "trainer/data/dataset.h"

namespace ecrf {
namespace trainer {

class RaySet {
 public:
  // `views` must outlive the RaySet.
  explicit RaySet(const std::vector<View>& views);

  size_t size() const { return active_.size(); }

  // Rays from these cameras (one per view, e.g. refined ones; must outlive the RaySet) instead of
  // the views' own; null: the views' cameras again.
  void UseCameras(const std::vector<Camera>* cameras);
  size_t total() const { return view_offset_.back(); }

  // Keeps the rays for which keep(origin, dir) holds; evaluated in parallel.
  void Filter(const std::function<bool(const float* origin, const float* dir)>& keep);
  // Same, for a test that runs on many rays at once: keep(n, origins, dirs, flags_out), called on
  // consecutive chunks (the callback parallelises internally). Keeps every ray and returns false
  // when fewer than min_keep would remain (training cannot go on with no rays).
  bool FilterChunked(const std::function<void(int n, const float* origins, const float* dirs,
                                              uint8_t* keep)>& keep,
                     size_t min_keep = 1);

  // The next n rays of a shuffled order (TensoRF's SimpleSampler: consecutive slices of a random
  // permutation, reshuffled when exhausted). Outputs are n x 3 each; views_or_null gets each
  // ray's view index (for per-image codes).
  void NextBatch(int n, std::mt19937_64& rng, float* origins, float* dirs, float* rgb,
                 uint32_t* views_or_null = nullptr);

  // n kept rays drawn uniformly with replacement, without moving NextBatch's position (a probe of
  // the training rays that leaves the training sequence as it was); views_or_null as NextBatch's.
  void Sample(int n, std::mt19937_64& rng, float* origins, float* dirs, float* rgb,
              uint32_t* views_or_null = nullptr) const;

  void Ray(uint32_t index, float origin[3], float dir[3], float rgb[3]) const;
  // The view a ray index belongs to.
  uint32_t ViewOf(uint32_t index) const;

  // For --resume: the sampler position is part of the training state.
  size_t cursor() const { return cursor_; }

  // An exact --resume: the kept rays as a bit set (16 bits to a float, the values checkpoints
  // store), the generator state the current permutation was drawn from (empty before the first
  // draw) and the position in it. Restoring redraws that permutation.
  void SaveState(std::vector<float>* keep, std::string* shuffle_rng, uint64_t* cursor) const;
  // Throws std::runtime_error when the state does not fit these views.
  void RestoreState(const std::vector<float>& keep, const std::string& shuffle_rng,
                    uint64_t cursor);

 private:
  // Ray() for an index whose view v is known.
  void RayInView(size_t v, uint32_t index, float origin[3], float dir[3], float rgb[3]) const;
  void Shuffle(std::mt19937_64& rng);
  void KeepFlagged(const std::vector<uint8_t>& flags);

  const std::vector<View>& views_;
  const std::vector<Camera>* cameras_ = nullptr;  // overrides views_[v].camera when set
  std::vector<uint64_t> view_offset_;             // prefix sums of pixels per view
  std::vector<uint32_t> active_;                  // global pixel indices of the kept rays
  std::vector<uint32_t> order_;                   // permutation of active_
  size_t cursor_ = 0;
  std::string shuffle_rng_;  // the generator before order_ was drawn
};

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_DATA_RAY_SET_H_
