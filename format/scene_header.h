// The HEAD chunk: everything a decoder must know before it allocates anything (SPEC.md 6.2).
// Writer and parser live together so the two cannot drift apart; the parser validates every
// field against the limits of SPEC.md section 8 and says which field is wrong.
#ifndef ECRF_FORMAT_SCENE_HEADER_H_
#define ECRF_FORMAT_SCENE_HEADER_H_

#include <cstddef>
#include <cstdint>

#include "format/byte_io.h"
#include "format/container.h"
#include "format/status.h"

namespace ecrf {

constexpr uint32_t kChunkHead = FourCC("HEAD");
constexpr uint32_t kChunkOccupancy = FourCC("OCCU");
constexpr uint32_t kChunkCoefficients = FourCC("COEF");
constexpr uint32_t kChunkMlpWeights = FourCC("MLPW");
constexpr uint32_t kChunkMetadata = FourCC("meta");

// Scene limits (SPEC.md section 8).
constexpr int kMaxSceneGridRes = 4096;  // per axis, feature grids and occupancy
constexpr int kMaxSceneRank = 1024;     // per mode and grid
constexpr uint64_t kMaxSceneGridValues = uint64_t{1} << 28;  // all planes and lines of a scene
constexpr uint64_t kMaxOccupancyVoxels = uint64_t{1} << 31;
constexpr uint32_t kMaxSceneSamples = 1u << 20;  // samples per ray
constexpr int kMaxSceneFeatureDim = 256;
constexpr int kMaxScenePeFreqs = 16;
constexpr int kMaxSceneHidden = 1024;
// hidden = 0: no MLP; the colour is a spherical-harmonics expansion in the view direction of
// degree 0 to 3 (SPEC.md 7.6.2), whose 3 (D + 1)^2 coefficients are the basis output
// (feature_dim), channel-major, and which needs version_minor 7 (2.1).
constexpr int kMaxShDegree = 3;
constexpr uint8_t kShColourMinVersionMinor = 7;
// The degree whose coefficients fill feature_dim (3 (D + 1)^2), or -1 when none does.
inline int ShDegreeForFeatureDim(int feature_dim) {
  for (int d = 0; d <= kMaxShDegree; ++d) {
    if (3 * (d + 1) * (d + 1) == feature_dim) return d;
  }
  return -1;
}

constexpr int kNumSceneGrids = 2;        // 0: density, 1: appearance
constexpr int kTensorsPerSceneGrid = 6;  // planes 0..2, then lines 0..2

// HEAD is 90 bytes up to version 1.8; from 1.9 a 91st byte, density_activation, follows. A
// stream of a minor version newer than this implementation's (kVersionMinor) may carry more bytes
// after it, for its later features: zero where those features are unused (SPEC.md 6.2).
constexpr size_t kSceneHeaderBytes = 90;
constexpr uint8_t kDensityActivationMinVersionMinor = 9;
inline size_t SceneHeaderBytes(int version_minor) {
  return version_minor >= kDensityActivationMinVersionMinor ? kSceneHeaderBytes + 1
                                                            : kSceneHeaderBytes;
}

// HEAD density_activation (SPEC.md 6.2, 7.4): how the density feature becomes sigma. TensoRF
// trains its synthetic scenes with softplus (a shift of -10 starts them empty) and its LLFF
// scenes with ReLU (no shift): on flower ReLU leaves 2.5x fewer coloured samples a ray for
// +0.2 dB at the same iterations (docs/real-captures.md).
enum class DensityActivation : uint8_t {
  kSoftplus = 0,  // softplus(feature + density_shift); every stream before 1.9
  kRelu = 1,      // max(feature + density_shift, 0); version 1.9
};
constexpr int kNumDensityActivations = 2;
constexpr const char* kDensityActivationNames[kNumDensityActivations] = {"softplus", "relu"};
// Its name; "unknown" for other values.
inline const char* DensityActivationName(DensityActivation a) {
  const int i = static_cast<int>(a);
  return i < kNumDensityActivations ? kDensityActivationNames[i] : "unknown";
}

// HEAD scene_model (SPEC.md 6.2).
enum class SceneModel : uint8_t {
  kObject = 0,     // the box is the scene: rays sample it with a fixed step (7.2)
  kUnbounded = 1,  // the box is the region of interest of a contracted, unbounded scene (7.2.1)
  kForward = 2,    // the box is in the NDC of a reference camera (NDCP chunk, 7.2.2)
};
constexpr int kNumSceneModels = 3;
// "object", "unbounded", "forward"; "unknown" for other values.
inline const char* SceneModelName(SceneModel m) {
  return m == SceneModel::kObject      ? "object"
         : m == SceneModel::kUnbounded ? "unbounded"
         : m == SceneModel::kForward   ? "forward"
                                       : "unknown";
}
// The container minor version a stream with this scene model needs at least (2.1).
constexpr uint8_t kSceneModelMinVersionMinor[kNumSceneModels] = {0, 2, 3};

struct SceneHeader {
  float aabb_min[3] = {-1.5f, -1.5f, -1.5f};
  float aabb_max[3] = {1.5f, 1.5f, 1.5f};
  uint16_t res[3] = {2, 2, 2};
  uint16_t ranks[kNumSceneGrids][3] = {{0, 0, 0}, {0, 0, 0}};
  float density_shift = -10.f;
  float distance_scale = 25.f;
  float step_size = 0.f;     // world units between samples
  uint32_t num_samples = 0;  // samples per ray
  float weight_threshold = 1e-4f;
  float near_far[2] = {2.f, 6.f};
  float background[3] = {1.f, 1.f, 1.f};
  uint16_t feature_dim = 27;
  uint8_t feature_pe_freqs = 2;
  uint8_t viewdir_pe_freqs = 2;
  uint16_t hidden = 128;  // 0: spherical-harmonics colour, no MLP (kMaxShDegree)
  uint8_t has_occupancy = 0;
  // 0: object (the box is the scene); 1: unbounded (the box is the region of interest of a
  // contracted scene, SPEC.md 7.2.1; streams of version 1.2); 2: forward-facing (the box is in
  // the NDC of the NDCP chunk's reference camera, 7.2.2; version 1.3). ecrf::SceneModel names them.
  uint8_t scene_model = 0;
  // A DensityActivation; written only from version 1.9 (kDensityActivationMinVersionMinor), 0
  // (softplus) in every older stream.
  uint8_t density_activation = 0;

  int total_rank(int grid) const { return ranks[grid][0] + ranks[grid][1] + ranks[grid][2]; }
};

// The HEAD payload of a stream of `version_minor`: SceneHeaderBytes(version_minor) bytes.
void WriteSceneHeader(const SceneHeader& header, int version_minor, ByteWriter* out);
// Parses and validates the HEAD payload of a stream of `version_minor`: exactly
// SceneHeaderBytes(version_minor) bytes, or more, all zero past those, when version_minor is newer
// than kVersionMinor.
Status ParseSceneHeader(const uint8_t* payload, size_t size, int version_minor,
                        SceneHeader* header);

// Number of float32 values of all twelve tensors (SPEC.md 6.2 GridValues).
uint64_t SceneGridValues(const SceneHeader& header);

// Extent of tensor t (0..5) of a grid as a block-DCT view (SPEC.md 6.4): planes
// {rank, res[v], res[u]}, lines {1, rank, res[w]}.
void SceneTensorExtent(const SceneHeader& header, int grid, int tensor, int extent[3]);
inline int SceneTensorRank(const SceneHeader& header, int grid, int tensor) {
  return header.ranks[grid][tensor % 3];
}

}  // namespace ecrf

#endif  // ECRF_FORMAT_SCENE_HEADER_H_
