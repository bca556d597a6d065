// Hand-made .ecrf conformance streams (SPEC.md section 6), built from integer coefficients with
// format/ only, so every platform writes the same bytes: the generator (`ecrf conformance`)
// and the tests rebuild them and compare with the checked-in files to detect format changes.
//
// Each exercises an edge of the syntax: rank-0 modes, 2D-only plane blocks, 16-bit
// coefficients with escapes, an occupancy mask, an empty occupancy mask, float16/float32 MLPs,
// a quantized MLP (bitstream 1.1) whose rows span 2^-3..2^3 in scale and whose largest levels
// take the class escape, an unbounded scene (bitstream 1.2: contracted space, SPEC.md 7.2.1) seen
// from outside its region of interest, a forward-facing scene (bitstream 1.3: NDC, 7.2.2) seen
// from in front of its reference camera. Those carry the lowest version of their features and
// the narrow coefficient contexts of 1.0-1.3; the `*_wide_contexts*` vectors are 1.4 streams,
// `scene_neighbour_contexts` a 1.5 stream, `scene_deferred_head` a 1.6 one, `scene_sh_*` 1.7,
// `scene_one_hidden_layer` 1.8.
// Added with SPEC.md 1.5: a quantized MLP whose levels reach every magnitude class up to 24 (the
// class escape with extra values up to 2^23), an unbounded scene whose rays end at their sample
// limit inside the contracted cube, and a forward-facing scene seen from the side, so that a
// quarter of the rays never reach the reference camera's far side and miss the NDC mapping.
#ifndef ECRF_CONFORMANCE_SCENE_VECTORS_H_
#define ECRF_CONFORMANCE_SCENE_VECTORS_H_

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "conformance/coef_vectors.h"
#include "format/byte_io.h"
#include "format/coefficients/coef_coder.h"
#include "format/container.h"
#include "format/half_float.h"
#include "format/mlp_coder.h"
#include "format/ndc_frame.h"
#include "format/occupancy_coder.h"
#include "format/scene_header.h"

namespace ecrf {
namespace conformance {

enum class OccupancyKind { kNone, kSphere, kEmpty };

struct SceneVector {
  const char* name;
  uint16_t res[3];
  uint16_t ranks[2][3];
  int plane_block[3];
  int line_block[3];
  int coef_bits;
  int mlp_precision;  // 0 float16, 1 float32, 2 quantized
  OccupancyKind occupancy;
  uint32_t seed;
  SceneModel scene_model;
  bool wide_contexts = false;  // a 1.4 stream: wide coefficient contexts in the plane chunks
  int num_samples = 0;         // samples per ray instead of the model's default (0)
  bool mlp_escapes = false;    // quantized MLP rows whose levels span classes 0..24
  // A 1.5 stream: neighbour coefficient contexts in the plane chunks, wide in the line chunks,
  // wide occupancy contexts.
  bool neighbour_contexts = false;
  HeadKind head = HeadKind::kPerSample;  // kDeferred: a 1.6 stream (SPEC.md 7.6)
  // 0..3: the spherical-harmonics colour of this degree (HEAD hidden 0, a 1.7 stream, 7.6.2).
  int sh_degree = -1;
  int hidden_layers = 2;  // 1: the MLP with one hidden layer (MLPW layers 1, a 1.8 stream, 6.6)
  // kRelu: HEAD density_activation 1, a 1.9 stream (6.2, 7.4).
  DensityActivation density_activation = DensityActivation::kSoftplus;
};

inline const std::vector<SceneVector>& SceneVectors() {
  static const std::vector<SceneVector> v = {
      {"scene_ranks_dropped",
       {12, 10, 9},
       {{0, 3, 2}, {2, 0, 3}},
       {4, 8, 8},
       {1, 4, 8},
       8,
       0,
       OccupancyKind::kNone,
       11,
       SceneModel::kObject},
      {"scene_2d_blocks",
       {20, 18, 16},
       {{2, 2, 2}, {3, 3, 3}},
       {1, 8, 8},
       {1, 1, 16},
       8,
       1,
       OccupancyKind::kSphere,
       12,
       SceneModel::kObject},
      {"scene_16bit",
       {9, 9, 9},
       {{2, 1, 2}, {2, 2, 1}},
       {2, 4, 4},
       {1, 2, 4},
       16,
       0,
       OccupancyKind::kSphere,
       13,
       SceneModel::kObject},
      {"scene_empty_occupancy",
       {8, 8, 8},
       {{1, 1, 1}, {1, 1, 1}},
       {1, 4, 4},
       {1, 1, 8},
       8,
       0,
       OccupancyKind::kEmpty,
       14,
       SceneModel::kObject},
      {"scene_quantized_mlp",
       {10, 12, 8},
       {{2, 2, 2}, {2, 3, 2}},
       {2, 4, 4},
       {1, 2, 8},
       8,
       2,
       OccupancyKind::kSphere,
       15,
       SceneModel::kObject},
      {"scene_unbounded",
       {16, 16, 16},
       {{2, 2, 2}, {2, 2, 2}},
       {2, 4, 4},
       {1, 2, 8},
       8,
       0,
       OccupancyKind::kSphere,
       16,
       SceneModel::kUnbounded},
      {"scene_forward",
       {16, 16, 16},
       {{2, 2, 2}, {2, 2, 2}},
       {2, 4, 4},
       {1, 2, 8},
       8,
       0,
       OccupancyKind::kSphere,
       17,
       SceneModel::kForward},
      {"scene_wide_contexts",
       {16, 14, 12},
       {{2, 2, 2}, {4, 4, 4}},
       {4, 8, 8},
       {1, 4, 8},
       8,
       2,
       OccupancyKind::kSphere,
       18,
       SceneModel::kObject,
       true},
      {"scene_wide_contexts_16bit",
       {9, 9, 9},
       {{2, 1, 2}, {2, 2, 1}},
       {2, 4, 4},
       {1, 2, 4},
       16,
       0,
       OccupancyKind::kSphere,
       19,
       SceneModel::kObject,
       true},
      {"scene_quantized_mlp_escapes",
       {10, 12, 8},
       {{2, 2, 2}, {2, 3, 2}},
       {2, 4, 4},
       {1, 2, 8},
       8,
       2,
       OccupancyKind::kSphere,
       20,
       SceneModel::kObject,
       false,
       0,
       true},
      {"scene_unbounded_sample_limit",
       {16, 16, 16},
       {{2, 2, 2}, {2, 2, 2}},
       {2, 4, 4},
       {1, 2, 8},
       8,
       0,
       OccupancyKind::kSphere,
       21,
       SceneModel::kUnbounded,
       false,
       50},
      {"scene_forward_side_view",
       {16, 16, 16},
       {{2, 2, 2}, {2, 2, 2}},
       {2, 4, 4},
       {1, 2, 8},
       8,
       0,
       OccupancyKind::kSphere,
       22,
       SceneModel::kForward},
      // Bitstream 1.5: plane chunks with the neighbour contexts over block grids of 1 x 2 x 2
      // (density) and 2 x 2 x 2 (appearance: ranks 5 and 6 in blocks of 4 channels, so the
      // second channel block is padded), lines with the wide ones, the mask with the wide
      // occupancy contexts.
      {"scene_neighbour_contexts",
       {16, 14, 12},
       {{2, 3, 2}, {5, 6, 5}},
       {4, 8, 8},
       {1, 4, 8},
       8,
       2,
       OccupancyKind::kSphere,
       23,
       SceneModel::kObject,
       false,
       0,
       false,
       true},
      // Added with SPEC.md 1.7 (bitstream 1.6): the deferred head, the MLP once per ray on the
      // weighted sum of its coloured samples' products, with a quantized MLP and a mask.
      {"scene_deferred_head",
       {12, 10, 11},
       {{2, 2, 2}, {3, 2, 3}},
       {2, 4, 4},
       {1, 2, 8},
       8,
       2,
       OccupancyKind::kSphere,
       24,
       SceneModel::kObject,
       false,
       0,
       false,
       false,
       HeadKind::kDeferred},
      // Added with SPEC.md 1.8 (bitstream 1.7): the spherical-harmonics colour (HEAD hidden 0),
      // degree 2 once per ray with a quantized basis, degree 3 per sample in binary16.
      {"scene_sh_deferred",
       {12, 10, 11},
       {{2, 2, 2}, {3, 2, 3}},
       {2, 4, 4},
       {1, 2, 8},
       8,
       2,
       OccupancyKind::kSphere,
       25,
       SceneModel::kObject,
       false,
       0,
       false,
       false,
       HeadKind::kDeferred,
       2},
      {"scene_sh_per_sample",
       {10, 12, 9},
       {{2, 2, 2}, {2, 3, 2}},
       {2, 4, 4},
       {1, 2, 8},
       8,
       0,
       OccupancyKind::kNone,
       26,
       SceneModel::kObject,
       false,
       0,
       false,
       false,
       HeadKind::kPerSample,
       3},
      // Added with SPEC.md 1.9 (bitstream 1.8): the MLP with one hidden layer (MLPW layers 1),
      // once per ray, quantized, with a mask.
      {"scene_one_hidden_layer",
       {11, 12, 10},
       {{2, 2, 2}, {3, 3, 2}},
       {2, 4, 4},
       {1, 2, 8},
       8,
       2,
       OccupancyKind::kSphere,
       27,
       SceneModel::kObject,
       false,
       0,
       false,
       false,
       HeadKind::kDeferred,
       -1,
       1},
      // Added with SPEC.md 1.10 (bitstream 1.9): ReLU density (HEAD density_activation 1) in a
      // forward-facing scene, as TensoRF trains LLFF.
      {"scene_relu_density",
       {16, 16, 16},
       {{2, 2, 2}, {2, 3, 2}},
       {2, 4, 4},
       {1, 2, 8},
       8,
       0,
       OccupancyKind::kSphere,
       28,
       SceneModel::kForward,
       false,
       0,
       false,
       false,
       HeadKind::kPerSample,
       -1,
       2,
       DensityActivation::kRelu},
  };
  return v;
}

inline SceneHeader SceneVectorHeader(const SceneVector& v) {
  SceneHeader h;
  for (int a = 0; a < 3; ++a) {
    h.aabb_min[a] = -1.f;
    h.aabb_max[a] = 1.f;
    h.res[a] = v.res[a];
    h.ranks[0][a] = v.ranks[0][a];
    h.ranks[1][a] = v.ranks[1][a];
  }
  h.aabb_max[2] = 0.75f;  // not a cube: axis conventions matter
  h.density_shift = -2.f;
  h.distance_scale = 25.f;
  h.step_size = 0.05f;
  h.num_samples = 120;
  h.weight_threshold = 1e-4f;
  h.near_far[0] = 1.f;
  h.near_far[1] = 6.f;
  h.background[0] = 1.f;
  h.background[1] = 0.5f;
  h.background[2] = 0.f;
  h.feature_dim = 6;
  h.feature_pe_freqs = 1;
  h.viewdir_pe_freqs = 2;
  h.hidden = 16;
  if (v.sh_degree >= 0) {
    h.hidden = 0;
    h.feature_dim = static_cast<uint16_t>(3 * (v.sh_degree + 1) * (v.sh_degree + 1));
    h.feature_pe_freqs = 0;
    h.viewdir_pe_freqs = 0;
  }
  h.has_occupancy = v.occupancy == OccupancyKind::kNone ? 0 : 1;
  h.scene_model = static_cast<uint8_t>(v.scene_model);
  h.density_activation = static_cast<uint8_t>(v.density_activation);
  // ReLU as trained (unshifted) and with a shift of -0.25 for samples at exactly 0 as well.
  if (v.density_activation == DensityActivation::kRelu) h.density_shift = -0.25f;
  if (v.scene_model == SceneModel::kUnbounded) {
    // The box is the region of interest; 12 / step_size samples cross the contracted cube.
    h.step_size = 0.05f;
    h.num_samples = 240;
    h.near_far[0] = 0.1f;
  }
  if (v.scene_model == SceneModel::kForward) {
    // The box is in NDC, narrower than the reference camera's view (x, y in [-1, 1]) so that the
    // render shows its edges; rays start on the near plane (t = 0) and cross it in about 2 units.
    h.aabb_min[0] = -0.55f;
    h.aabb_max[0] = 0.6f;
    h.aabb_min[1] = -0.5f;
    h.aabb_max[1] = 0.45f;
    h.step_size = 0.05f;
    h.num_samples = 120;
    h.near_far[0] = 0.f;
    h.near_far[1] = 10.f;
  }
  if (v.num_samples > 0) h.num_samples = static_cast<uint32_t>(v.num_samples);
  return h;
}

// The forward vector's reference camera: about the conformance camera OrbitCamera(48, 48, 0.7,
// 0.5, 3.5) moved back by 0.5 (the world origin at depth 4), in decimal constants so that every
// platform writes the same bytes. Scale 2.75 is its own 2 fx / width, not the render camera's
// (2.7778): the reference camera is a camera of its own (SPEC.md 7.7).
inline NdcFrame SceneVectorNdcFrame() {
  NdcFrame f;
  const float m[12] = {-0.644218f, 0.764842f, 0.f,       0.f,       -0.366685f, -0.308854f,
                       0.877583f,  0.f,       0.671212f, 0.565354f, 0.479426f,  -4.f};
  for (int k = 0; k < 12; ++k) f.world_to_ref[k] = m[k];
  f.scale[0] = 2.75f;
  f.scale[1] = 2.75f;
  f.near_plane = 1.5f;
  return f;
}

// The box the grids and the occupancy mask span: the HEAD box, or the contracted cube.
inline void SceneVectorGridBox(const SceneVector& v, const SceneHeader& h, float lo[3],
                               float hi[3]) {
  for (int a = 0; a < 3; ++a) {
    lo[a] = v.scene_model == SceneModel::kUnbounded ? -2.f : h.aabb_min[a];
    hi[a] = v.scene_model == SceneModel::kUnbounded ? 2.f : h.aabb_max[a];
  }
}

// Coefficients of one block: a strong DC, decaying lower frequencies, some zero blocks.
inline void MakeSceneBlock(Lcg& rng, const int dims[3], int32_t max_abs, bool density, int32_t* q) {
  const int volume = dims[0] * dims[1] * dims[2];
  for (int i = 0; i < volume; ++i) q[i] = 0;
  if (rng.Below(5) == 0) return;
  const int32_t dc_scale = max_abs > 127 ? 20000 : 100;
  for (int i0 = 0; i0 < dims[0]; ++i0)
    for (int i1 = 0; i1 < dims[1]; ++i1)
      for (int i2 = 0; i2 < dims[2]; ++i2) {
        const int f = i0 + i1 + i2;
        const int bound = dc_scale / (1 + 2 * f * f);
        if (bound == 0 || rng.Below(3) == 0) continue;
        int32_t m = int32_t(rng.Below(bound + 1));
        if (f == 0 && density) m = bound;  // positive density features: visible surfaces
        if (m > max_abs) m = max_abs;
        q[(i0 * dims[1] + i1) * dims[2] + i2] = (f == 0 || (rng.Next() & 1)) ? m : -m;
      }
}

// The lowest minor version that has every feature the vector uses. 1.1: quantized MLP; 1.2:
// unbounded scene model; 1.3: forward-facing scene model; 1.4: wide coefficient contexts; 1.5:
// neighbour coefficient contexts; 1.6: the deferred head; 1.7: spherical-harmonics colour; 1.8:
// one hidden layer.
inline uint8_t SceneVectorVersionMinor(const SceneVector& v) {
  return std::max<uint8_t>(
      {v.neighbour_contexts ? kNeighbourContextsMinVersionMinor
       : v.wide_contexts    ? kWideContextsMinVersionMinor
                            : uint8_t{0},
       kSceneModelMinVersionMinor[static_cast<int>(v.scene_model)],
       v.mlp_precision == kMlpPrecisionQuantized ? kQuantizedMlpMinVersionMinor : uint8_t{0},
       kHeadKindMinVersionMinor[static_cast<int>(v.head)],
       v.sh_degree >= 0 ? kShColourMinVersionMinor : uint8_t{0},
       v.hidden_layers == 1 ? kOneHiddenLayerMinVersionMinor : uint8_t{0},
       v.density_activation != DensityActivation::kSoftplus ? kDensityActivationMinVersionMinor
                                                            : uint8_t{0}});
}

// The occupancy chunk: a 7x6x5 mask over the grid box, empty or a sphere.
inline std::vector<uint8_t> SceneVectorOccupancyChunk(const SceneVector& v, const SceneHeader& h) {
  ByteWriter occ;
  const int mres[3] = {7, 6, 5};
  float lo[3], hi[3];
  SceneVectorGridBox(v, h, lo, hi);
  for (float x : lo) occ.F32(x);
  for (float x : hi) occ.F32(x);
  for (int r : mres) occ.U16(uint16_t(r));
  // The 1.5 vector codes its mask with the wide occupancy contexts.
  const OccupancyContextSet occupancy_set =
      v.neighbour_contexts ? OccupancyContextSet::kWide : OccupancyContextSet::kNarrow;
  occ.U16(static_cast<uint16_t>(occupancy_set));
  std::vector<uint8_t> voxels(size_t(mres[0]) * mres[1] * mres[2], 0);
  if (v.occupancy == OccupancyKind::kSphere) {
    for (int z = 0; z < mres[2]; ++z)
      for (int y = 0; y < mres[1]; ++y)
        for (int x = 0; x < mres[0]; ++x) {
          const double dx = x / 3.0 - 1, dy = y / 2.5 - 1, dz = z / 2.0 - 1;
          voxels[(size_t(z) * mres[1] + y) * mres[0] + x] = dx * dx + dy * dy + dz * dz < 0.8;
        }
  }
  occ.Bytes(EncodeOccupancy(voxels.data(), mres, occupancy_set));
  return occ.bytes();
}

// Adds the coefficient chunk of tensor t (planes 0-2, lines 3-5) of grid g (0 density, 1
// appearance), its blocks drawn from rng. False when its contexts cannot be set up.
inline bool AddSceneVectorCoefficientChunk(const SceneVector& v, const SceneHeader& h, int g, int t,
                                           Lcg& rng, ContainerWriter& writer) {
  const int32_t max_abs = v.coef_bits == 16 ? 32767 : 127;
  const int* dims = t < 3 ? v.plane_block : v.line_block;
  int extent[3];
  SceneTensorExtent(h, g, t, extent);
  int blocks = 1, grid[3];
  for (int a = 0; a < 3; ++a) {
    grid[a] = (extent[a] + dims[a] - 1) / dims[a];
    blocks *= grid[a];
  }
  CoefContexts ctx;
  // The 1.4 vectors code planes with the wide set and lines with the narrow one, the 1.5
  // vector planes with the neighbour set and lines with the wide one: the set is chosen per
  // chunk.
  const CoefContextSet set = v.neighbour_contexts
                                 ? (t < 3 ? CoefContextSet::kNeighbour : CoefContextSet::kWide)
                             : v.wide_contexts && t < 3 ? CoefContextSet::kWide
                                                        : CoefContextSet::kNarrow;
  if (!ctx.Init(BlockShape{dims[0], dims[1], dims[2]}, set, grid, static_cast<size_t>(-1)).ok()) {
    return false;
  }
  RangeEncoder enc;
  std::vector<int32_t> q(size_t(dims[0]) * dims[1] * dims[2]);
  for (int b = 0; b < blocks; ++b) {
    MakeSceneBlock(rng, dims, max_abs, g == 0, q.data());
    EncodeCoefBlock(enc, ctx, q.data());
  }
  ByteWriter c;
  c.U8(uint8_t(g));
  c.U8(uint8_t(t));
  c.U8(uint8_t(v.coef_bits));
  c.U8(static_cast<uint8_t>(set));
  for (int a = 0; a < 3; ++a) c.U8(uint8_t(dims[a]));
  c.U8(0);
  // The unbounded vector's density is translucent: samples far along its rays count too.
  const float density_step = v.scene_model == SceneModel::kUnbounded ? 0.00390625f : 0.125f;
  c.F32(v.coef_bits == 16 ? 0.0005f : (g == 0 ? density_step : 0.03125f));
  c.Bytes(enc.Finish());
  writer.AddChunk(kChunkCoefficients, c.bytes());
  return true;
}

// The MLP weights chunk, in the layout of decoder/mlp.h: small values on a 1/256 lattice, drawn
// from rng.
inline std::vector<uint8_t> SceneVectorMlpChunk(const SceneVector& v, const SceneHeader& h,
                                                Lcg& rng) {
  const int F = h.feature_dim, H = h.hidden, P = h.total_rank(1);
  const MlpLayout layout =
      MakeMlpLayout(F, P, H, h.feature_pe_freqs, h.viewdir_pe_freqs, v.hidden_layers);
  const size_t count = MlpParamCount(layout);
  ByteWriter mlp;
  mlp.U8(uint8_t(v.mlp_precision));
  mlp.U8(static_cast<uint8_t>(v.head));
  mlp.U8(v.hidden_layers == 1 ? kMlpOneHiddenLayer : kMlpTwoHiddenLayers);
  mlp.U8(0);
  if (v.mlp_precision == kMlpPrecisionQuantized && v.mlp_escapes) {
    // Magnitudes 2^(1 - k) (k = i % 25) times a factor in [1, 2) so that with 2^24 - 1 levels
    // each row of 25 or more weights holds levels of every class 0..24: escapes with every extra
    // value up to 2^23 - 1. The row steps come out near 2^-23, subnormal binary16 numbers (the
    // largest levels clip to 2^24 - 1); weights below 4 keep the colours off saturation, so that
    // renderers agree within the tolerance of SPEC.md 7.7.
    std::vector<float> w(count);
    for (size_t i = 0; i < count; ++i) {
      const float m = 1.f + float(rng.Below(256)) / 256.f;
      const float sign = (rng.Next() & 1) ? -1.f : 1.f;
      w[i] = sign * std::ldexp(m, 1 - int(i % 25));
    }
    mlp.Bytes(EncodeQuantizedMlp(layout, w.data(), kMlpMaxLevel, nullptr));
  } else if (v.mlp_precision == kMlpPrecisionQuantized) {
    // Rows of very different scale (one step each); 20000 levels per row reach class 15.
    std::vector<float> w(count);
    for (size_t i = 0; i < count; ++i) {
      w[i] = std::ldexp(float(int(rng.Below(257)) - 128) / 256.f, int(i / 7 % 7) - 3);
    }
    mlp.Bytes(EncodeQuantizedMlp(layout, w.data(), 20000, nullptr));
  }
  for (size_t i = 0; i < count && v.mlp_precision != kMlpPrecisionQuantized; ++i) {
    const float w = float(int(rng.Below(257)) - 128) / 256.f;
    if (v.mlp_precision == 1) {
      mlp.F32(w);
    } else {
      mlp.U16(FloatToHalf(w));
    }
  }
  return mlp.bytes();
}

// The vector's file: the chunks in file order, every random draw from one generator seeded by
// the vector (blocks of the coefficient chunks, then the MLP weights). Empty when a coefficient
// chunk cannot be built.
inline std::vector<uint8_t> BuildSceneVector(const SceneVector& v) {
  const SceneHeader h = SceneVectorHeader(v);
  Lcg rng(v.seed);
  const uint8_t version_minor = SceneVectorVersionMinor(v);
  ContainerWriter writer(version_minor);
  ByteWriter head;
  WriteSceneHeader(h, version_minor, &head);
  writer.AddChunk(kChunkHead, head.bytes());
  if (v.scene_model == SceneModel::kForward) {
    ByteWriter ndc;
    WriteNdcFrame(SceneVectorNdcFrame(), &ndc);
    writer.AddChunk(kChunkNdcFrame, ndc.bytes());
  }
  if (h.has_occupancy) writer.AddChunk(kChunkOccupancy, SceneVectorOccupancyChunk(v, h));
  for (int g = 0; g < 2; ++g) {
    for (int t = 0; t < 6; ++t) {
      if (h.ranks[g][t % 3] == 0) continue;
      if (!AddSceneVectorCoefficientChunk(v, h, g, t, rng, writer)) return {};
    }
  }
  writer.AddChunk(kChunkMlpWeights, SceneVectorMlpChunk(v, h, rng));
  const std::string meta = std::string("{\"vector\":\"") + v.name + "\"}";
  writer.AddChunk(kChunkMetadata, reinterpret_cast<const uint8_t*>(meta.data()), meta.size());
  return writer.Finish();
}

}  // namespace conformance
}  // namespace ecrf

#endif  // ECRF_CONFORMANCE_SCENE_VECTORS_H_
