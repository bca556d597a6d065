// SceneField: the in-memory model of one decoded TensoRF VM scene, as the renderer consumes it.
//
// Conventions shared with the trainer (format/vm_modes.h): plane m spans u = kMatMode[m][0]
//   (columns) and v = kMatMode[m][1] (rows), line m spans w = kVecMode[m]; channels-last storage:
//   plane m [res[v]][res[u]][rank[m]], line m [res[w]][rank[m]]. Ranks may be 0.
// Grids are float32 or int16 fixed point with one scale per tensor (value = q * scale).
//
// Memory is held in HeapArray (malloc/free, no exceptions): every allocation is overflow-checked
// and capped (kMaxAllocationBytes) and reports kErrOutOfMemory / kErrLimit as a Status.
// The out-of-line parts (Allocate, Validate, mask queries) live in field_sampler.cc.
#ifndef ECRF_DECODER_FIELD_H_
#define ECRF_DECODER_FIELD_H_

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <type_traits>

#include "decoder/mlp.h"
#include "decoder/occupancy_rule.h"
#include "format/mlp_coder.h"
#include "format/ndc_frame.h"
#include "format/scene_header.h"
#include "format/status.h"
#include "format/vm_modes.h"

namespace ecrf {
namespace dec {

// Decoder limits (checked before allocating).
inline constexpr int kMaxGridRes = 4096;                        // per axis, grids and alpha mask
inline constexpr int kMaxRank = 1024;                           // per mode
inline constexpr size_t kMaxAllocationBytes = size_t{1} << 30;  // one array

// *out = a * b; false on size_t overflow.
inline bool CheckedMul(size_t a, size_t b, size_t* out) {
  if (a != 0 && b > static_cast<size_t>(-1) / a) return false;
  *out = a * b;
  return true;
}

// Owning, zero-initialised array of a trivially copyable type; move-only, never throws.
template <typename T>
class HeapArray {
  static_assert(std::is_trivially_copyable<T>::value, "HeapArray holds plain data only");

 public:
  HeapArray() = default;
  ~HeapArray() { std::free(data_); }
  HeapArray(const HeapArray&) = delete;
  HeapArray& operator=(const HeapArray&) = delete;
  HeapArray(HeapArray&& o) noexcept : data_(o.data_), size_(o.size_) {
    o.data_ = nullptr;
    o.size_ = 0;
  }
  HeapArray& operator=(HeapArray&& o) noexcept {
    if (this != &o) {
      std::free(data_);
      data_ = o.data_;
      size_ = o.size_;
      o.data_ = nullptr;
      o.size_ = 0;
    }
    return *this;
  }

  // Replaces the contents by `count` zero elements (count 0 releases the memory).
  Status Allocate(size_t count, size_t max_bytes = kMaxAllocationBytes) {
    Reset();
    if (count == 0) return Status::Ok();
    size_t bytes = 0;
    ECRF_CHECK_OR_RETURN(CheckedMul(count, sizeof(T), &bytes) && bytes <= max_bytes, kErrLimit,
                         "allocation of %zu elements of %zu bytes exceeds the limit of %zu bytes",
                         count, sizeof(T), max_bytes);
    data_ = static_cast<T*>(std::calloc(count, sizeof(T)));
    ECRF_CHECK_OR_RETURN(data_ != nullptr, kErrOutOfMemory, "out of memory (%zu bytes)", bytes);
    size_ = count;
    return Status::Ok();
  }
  void Reset() {
    std::free(data_);
    data_ = nullptr;
    size_ = 0;
  }

  T* data() { return data_; }
  const T* data() const { return data_; }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T& operator[](size_t i) { return data_[i]; }
  const T& operator[](size_t i) const { return data_[i]; }

 private:
  T* data_ = nullptr;
  size_t size_ = 0;
};

enum class GridStorage : uint8_t { kFloat32 = 0, kInt16 = 1 };

// One VM grid (density or appearance). Only the arrays of `storage` are allocated.
struct VmGrid {
  int res[3] = {0, 0, 0};
  int ranks[3] = {0, 0, 0};
  GridStorage storage = GridStorage::kFloat32;
  HeapArray<float> plane_f32[3], line_f32[3];
  HeapArray<int16_t> plane_i16[3], line_i16[3];
  float plane_scale[3] = {1.f, 1.f, 1.f};  // int16 only: value = q * scale
  float line_scale[3] = {1.f, 1.f, 1.f};

  // res[a] in [2, kMaxGridRes], ranks[m] in [0, kMaxRank]; zero-filled tensors, scales 1.
  Status Allocate(const int res_in[3], const int ranks_in[3], GridStorage storage_in);
  int total_rank() const { return ranks[0] + ranks[1] + ranks[2]; }
  int rank_offset(int m) const { return m == 0 ? 0 : (m == 1 ? ranks[0] : ranks[0] + ranks[1]); }
  size_t plane_count(int m) const {
    return static_cast<size_t>(res[kMatMode[m][1]]) * res[kMatMode[m][0]] * ranks[m];
  }
  size_t line_count(int m) const { return static_cast<size_t>(res[kVecMode[m]]) * ranks[m]; }
  // Memory the values hold in this storage.
  size_t StorageBytes() const {
    size_t n = 0;
    for (int m = 0; m < 3; ++m) n += plane_count(m) + line_count(m);
    return n * (storage == GridStorage::kInt16 ? 2 : 4);
  }
  // Element index inside plane m (y along v, x along u) and line m.
  size_t plane_index(int m, int y, int x, int r) const {
    return (static_cast<size_t>(y) * res[kMatMode[m][0]] + x) * ranks[m] + r;
  }
  size_t line_index(int m, int i, int r) const { return static_cast<size_t>(i) * ranks[m] + r; }
  // Consistent shapes, allocated arrays, finite positive scales (int16).
  // Shapes and allocations; with check_values also that every float32 value is finite.
  Status Validate(const char* what, bool check_values = true) const;
};

// TensoRF AlphaGridMask: a 0/1 volume over its own aabb (usually the scene's), sampled
// trilinearly with align_corners=True and zero padding; a point is occupied when the value is
// > 0, i.e. when a corner with non-zero interpolation weight is set. Bits are packed
// [z][y][x] (x fastest), bit i in byte i/8 at position i%8 (LSB first).
class OccupancyMask {
 public:
  // Cells per block edge, coarse to fine (powers of two: kBlock = 1 << kBlockShift). Each block
  // lies inside its block of every coarser level. The coarsest level is pooled from the next one.
  static constexpr int kLevels = 3;
  static constexpr int kBlockShift[kLevels] = {6, 4, 2};
  static constexpr int kBlock[kLevels] = {64, 16, 4};

  Status Init(const float aabb_min[3], const float aabb_max[3], const int res[3]);
  const int* res() const { return res_; }
  const float* aabb_min() const { return min_; }
  const float* aabb_max() const { return max_; }
  size_t voxel_count() const { return static_cast<size_t>(res_[0]) * res_[1] * res_[2]; }
  uint8_t* bits() { return bits_.data(); }
  const uint8_t* bits() const { return bits_.data(); }
  size_t bits_bytes() const { return bits_.size(); }
  bool Get(int x, int y, int z) const {
    const size_t i = (static_cast<size_t>(z) * res_[1] + y) * res_[0] + x;
    return (bits_[i >> 3] >> (i & 7)) & 1;
  }
  // Invalidates the acceleration (call BuildAcceleration again). Writes through bits() do not.
  void Set(int x, int y, int z, bool on) {
    accel_ready_ = false;
    const size_t i = (static_cast<size_t>(z) * res_[1] + y) * res_[0] + x;
    if (on) {
      bits_[i >> 3] = static_cast<uint8_t>(bits_[i >> 3] | (1u << (i & 7)));
    } else {
      bits_[i >> 3] = static_cast<uint8_t>(bits_[i >> 3] & ~(1u << (i & 7)));
    }
  }
  // Rebuilds the max-pooled block levels used for empty-space skipping. Call after the bits
  // change and before rendering.
  Status BuildAcceleration();
  bool acceleration_ready() const { return accel_ready_; }
  size_t occupied_count() const { return occupied_; }

  // Continuous mask index of a world point, computed exactly as TensoRF does in float:
  // c = (p - min) * 2/(max - min) - 1, idx = (c + 1)/2 * (res - 1).
  void Index(const float p[3], float idx[3]) const {
    for (int a = 0; a < 3; ++a) {
      const float c = (p[a] - min_[a]) * inv_size_[a] - 1.f;
      idx[a] = (c + 1.f) / 2.f * static_cast<float>(res_[a] - 1);
    }
  }
  // Trilinear mask value > 0 at mask index idx (exact reference test). Inline, as EmptyBlock.
  bool OccupiedAtIndex(const float idx[3]) const {
    return AnyWeightedCornerSet(idx, res_, [this](int x, int y, int z) { return Get(x, y, z); });
  }
  // Block of `level` containing idx (all idx in [0, res-1]); true when that block's corners
  // are all empty. lo/hi receive the block's closed corner range per axis.
  // Inline: the renderer asks at most once per level at every marched position.
  bool EmptyBlock(int level, const float idx[3], int lo[3], int hi[3]) const {
    const int B = kBlock[level], shift = kBlockShift[level];
    int b[3];
    for (int a = 0; a < 3; ++a) {
      int i = static_cast<int>(idx[a]);  // idx >= 0 (checked by the caller): a shift is i / B
      b[a] = i >> shift;
      if (b[a] > dims_[level][a] - 1) b[a] = dims_[level][a] - 1;
      lo[a] = b[a] * B;
      hi[a] = lo[a] + B;
      if (hi[a] > res_[a] - 1) hi[a] = res_[a] - 1;
    }
    return blocks_[level][(static_cast<size_t>(b[2]) * dims_[level][1] + b[1]) * dims_[level][0] +
                          b[0]] == 0;
  }
  // The finest level's empty radius: for each finest block, the chessboard radius (in blocks,
  // at most kEmptyRadiusCap) of the cube of finest blocks around it that are all empty, blocks
  // outside the grid counting as empty. Near the scene's surface, where the aligned blocks are
  // small, the cube lets a ray skip several blocks at once. Built only for masks of at most
  // kMaxRadiusBlocks finest blocks, so that its time is bounded whatever the stream declares.
  static constexpr int kEmptyRadiusCap = 8;
  static constexpr size_t kMaxRadiusBlocks = size_t{1} << 21;
  // lo/hi: the closed range of an empty finest block (from EmptyBlock); widened to the closed
  // voxel range of the empty cube around it. Returns its radius; 0 (lo/hi unchanged) without a
  // radius map.
  int EmptyCube(int lo[3], int hi[3]) const {
    constexpr int L = kLevels - 1, B = kBlock[L], shift = kBlockShift[L];
    if (radius_.empty()) return 0;
    int b[3];
    for (int a = 0; a < 3; ++a) b[a] = lo[a] >> shift;
    const int k = radius_[(static_cast<size_t>(b[2]) * dims_[L][1] + b[1]) * dims_[L][0] + b[0]];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(0, (b[a] - k) * B);
      hi[a] = std::min((b[a] + k + 1) * B, res_[a] - 1);
    }
    return k;
  }

 private:
  // Marks the blocks of every level but the coarsest whose closed corner range holds set voxel
  // (x, y, z).
  void MarkBlocks(int x, int y, int z);
  Status BuildEmptyRadius();

  float min_[3] = {0.f, 0.f, 0.f};
  float max_[3] = {0.f, 0.f, 0.f};
  float inv_size_[3] = {0.f, 0.f, 0.f};  // 2 / (max - min)
  int res_[3] = {0, 0, 0};
  HeapArray<uint8_t> bits_;
  // Level l: dims = ceil((res - 1) / kBlock[l]) blocks per axis; 1 byte per block: any corner
  // in the block's closed range [b*B, min((b+1)*B, res-1)] set.
  int dims_[kLevels][3] = {};
  HeapArray<uint8_t> blocks_[kLevels];
  HeapArray<uint8_t> radius_;  // finest level; empty when not built
  size_t occupied_ = 0;
  bool accel_ready_ = false;
};

// Everything the renderer needs for one scene.
struct SceneField {
  // kObject: the box is the scene and the grids span it. kUnbounded: the box is the region of
  // interest; world points are contracted (decoder/contraction.h) and the grids and the mask
  // span the contracted cube [-2, 2]^3 (SPEC.md 7.2.1). kForward: the box, grids and mask are in
  // the NDC of `ndc`'s reference camera (decoder/ndc.h, SPEC.md 7.2.2).
  SceneModel scene_model = SceneModel::kObject;
  NdcFrame ndc;
  float aabb_min[3] = {-1.5f, -1.5f, -1.5f};
  float aabb_max[3] = {1.5f, 1.5f, 1.5f};
  int res[3] = {0, 0, 0};       // grid resolution (density and appearance)
  float density_shift = -10.f;  // sigma = activation(feature + density_shift)
  DensityActivation density_activation = DensityActivation::kSoftplus;
  float distance_scale = 25.f;  // alpha = 1 - exp(-sigma * dist * distance_scale)
  float step_ratio = 0.5f;
  float weight_threshold = 1e-4f;  // colour only where weight > this
  float near_far[2] = {2.f, 6.f};
  float background[3] = {1.f, 1.f, 1.f};
  // 0: derived as TensoRF does (step = mean((max-min)/(res-1)) * step_ratio,
  // n_samples = int(|res| / step_ratio)). Store them explicitly when the trainer's values differ
  // (TensoRF keeps nSamples from before the final shrink).
  float step_size = 0.f;
  int n_samples = 0;

  VmGrid density;
  VmGrid appearance;
  bool has_mask = false;
  OccupancyMask mask;
  AppearanceMlp mlp;
  HeadKind head = HeadKind::kPerSample;  // where the MLP runs (SPEC.md 7.6)

  // Object: world units; unbounded: contracted units (derived from the cube [-2, 2]^3).
  float StepSize() const;
  int NumSamples() const;
  // Shapes agree (grid res == res, mlp num_products == appearance total rank), values finite,
  // mask accelerated. The renderer calls it before every frame batch.
  Status Validate() const;

  // Set by DecodeScene: the grids hold IDCT outputs times finite steps, finite by construction, so
  // Validate (run before every render) skips scanning every value. Code that writes the grids
  // itself leaves it false (or resets it) and Validate checks them.
  bool grids_known_finite = false;
};

}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_DECODER_FIELD_H_
