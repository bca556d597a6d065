// Small streams that are valid (or were, before the budgets of SPEC.md 8) and cost a decoder or a
// renderer far more than their size suggests: the cases of the work and decode budgets. Built
// with format/ only.
//
//   WideHeadStream:   the widest head the limits allow, every sample coloured (render work).
//   ManySamplesStream: a head of the given width, 16384 translucent samples per ray, every one
//                      coloured or (hidden = 0 in the options) none (density work).
//   EmptyRowsOccupancyStream: an OCCU chunk that flags every row and sets no voxel (decode).
//   FullLengthBlocksStream: COEF blocks whose end of block is the last position (decode).
#ifndef ECRF_CONFORMANCE_COSTLY_STREAMS_H_
#define ECRF_CONFORMANCE_COSTLY_STREAMS_H_

#include <cstdint>
#include <vector>

#include "format/byte_io.h"
#include "format/coefficients/coef_coder.h"
#include "format/container.h"
#include "format/mlp_coder.h"
#include "format/occupancy_contexts.h"
#include "format/scene_header.h"

namespace ecrf {
namespace costly {

struct CostlyScene {
  uint16_t res = 2;
  uint16_t density_rank = 1;
  uint16_t appearance_rank = 1;  // per mode: P = 3 x this
  int feature_dim = 4;
  int hidden = 8;
  int pe_freqs = 0;  // Ff = Fv
  int num_samples = 16384;
  float weight_threshold = 0.f;  // 0: every sample of positive weight is coloured
  // How coefficient blocks are coded: 0 all-zero blocks (coded = 0), 1 one coefficient at the
  // last scan position of every block (eob = V), over blocks of block^3 (planes; lines 1 x b x b).
  int blocks = 0;
  int block = 4;
  // An OCCU chunk over the grid box: 0 none; 1 every row flagged, no voxel set; 2 no row flagged
  // (an empty mask: every sample is skipped, but an unbounded ray still marches them all).
  int occupancy = 0;
  int occupancy_res = 2;
  int occupancy_depth = 0;  // the mask's z resolution (0: occupancy_res)
  // Bytes of an ancillary `meta` chunk: a larger stream, so a larger decode budget (SPEC.md 8).
  size_t padding = 0;
  bool neighbour = false;  // COEF chunks with the neighbour contexts (version 1.5, SPEC.md 4.4)
  bool unbounded = false;  // scene_model 1: samples spaced in contracted distance (SPEC.md 7.2.1)
};

// The classes the budgets of SPEC.md 8 were made for (tests, must-reject vectors, `ecrf bench
// budgets`).
// The widest head the limits allow (F 256, H 1024, P 3072, 16 frequencies): 10.7 M per sample.
inline CostlyScene WidestHead() {
  CostlyScene s;
  s.appearance_rank = 1024;
  s.feature_dim = 256;
  s.hidden = 1024;
  s.pe_freqs = 16;
  return s;
}
// An n^3 OCCU that flags every row and sets no voxel.
inline CostlyScene EmptyFlaggedRows(int n) {
  CostlyScene s;
  s.occupancy = 1;
  s.occupancy_res = n;
  return s;
}
// 2048^2 planes of rank 1 in 16^3 blocks, coded with the neighbour contexts (1.5): a few hundred
// bytes whose decode allocates and clears the contexts of 2048^2 / 16^2 blocks per plane.
inline CostlyScene NeighbourContexts2048() {
  CostlyScene s;
  s.res = 2048;
  s.block = 16;
  s.neighbour = true;
  s.weight_threshold = 1.f;
  return s;
}
// 512^2 planes of rank 16 in block^3 blocks (4^2 for lines), each coded to its last position.
inline CostlyScene FullLengthBlocks(int block) {
  CostlyScene s;
  s.res = 512;
  s.density_rank = 16;
  s.appearance_rank = 16;
  s.blocks = 1;
  s.block = block;
  return s;
}

// The MLPW chunk: quantized, every weight 0 (a few bytes however wide the head is).
inline std::vector<uint8_t> ZeroMlpChunk(const SceneHeader& h) {
  const MlpLayout layout = MakeMlpLayout(h.feature_dim, h.total_rank(1), h.hidden,
                                         h.feature_pe_freqs, h.viewdir_pe_freqs);
  std::vector<float> w(MlpParamCount(layout), 0.f);
  ByteWriter mlp;
  mlp.U8(kMlpPrecisionQuantized);
  mlp.U8(0);
  mlp.U8(0);
  mlp.U8(0);
  mlp.Bytes(EncodeQuantizedMlp(layout, w.data(), 127, nullptr));
  return mlp.bytes();
}

inline std::vector<uint8_t> BuildCostlyStream(const CostlyScene& cs) {
  SceneHeader h;
  for (int a = 0; a < 3; ++a) {
    h.aabb_min[a] = -1.f;
    h.aabb_max[a] = 1.f;
    h.res[a] = cs.res;
    h.ranks[0][a] = cs.density_rank;
    h.ranks[1][a] = cs.appearance_rank;
  }
  // sigma = softplus(-10) ~ 4.5e-5: every sample is translucent (alpha ~ 1e-7 at 16384 samples
  // across the box, the smallest a binary32 1 - exp(-x) resolves), so transmittance never drops
  // enough to stop a ray early and every weight is positive.
  h.density_shift = -10.f;
  h.distance_scale = 25.f;
  h.step_size = 2.f / static_cast<float>(cs.num_samples);
  h.num_samples = static_cast<uint32_t>(cs.num_samples);
  h.weight_threshold = cs.weight_threshold;
  h.near_far[0] = 0.5f;
  h.near_far[1] = 6.f;
  h.feature_dim = static_cast<uint16_t>(cs.feature_dim);
  h.feature_pe_freqs = static_cast<uint8_t>(cs.pe_freqs);
  h.viewdir_pe_freqs = static_cast<uint8_t>(cs.pe_freqs);
  h.hidden = static_cast<uint16_t>(cs.hidden);
  h.has_occupancy = cs.occupancy != 0;
  h.scene_model = static_cast<uint8_t>(cs.unbounded ? SceneModel::kUnbounded : SceneModel::kObject);
  const float extent = cs.unbounded ? 2.f : 1.f;  // the box the grids and the mask span
  // The quantized MLP is a 1.1 feature, the unbounded model 1.2, the neighbour contexts 1.5.
  const uint8_t version_minor = cs.neighbour ? 5 : (cs.unbounded ? 2 : 1);
  ContainerWriter writer(version_minor);
  ByteWriter head;
  WriteSceneHeader(h, version_minor, &head);
  writer.AddChunk(kChunkHead, head.bytes());
  if (cs.occupancy != 0) {
    ByteWriter occ;
    for (int a = 0; a < 3; ++a) occ.F32(-extent);
    for (int a = 0; a < 3; ++a) occ.F32(extent);
    const int n = cs.occupancy_res, depth = cs.occupancy_depth > 0 ? cs.occupancy_depth : n;
    occ.U16(static_cast<uint16_t>(n));
    occ.U16(static_cast<uint16_t>(n));
    occ.U16(static_cast<uint16_t>(depth));
    occ.U16(0);
    // Rows flagged (or not), every voxel 0: SPEC.md 6.3's syntax, coded with its contexts.
    const int flag = cs.occupancy == 1 ? 1 : 0;
    std::vector<uint8_t> row_any(static_cast<size_t>(n) * depth, 0);
    occupancy_internal::OccupancyContexts ctx;
    RangeEncoder enc;
    for (int z = 0; z < depth; ++z) {
      for (int y = 0; y < n; ++y) {
        enc.EncodeBool(flag, ctx.row[occupancy_internal::RowContext(row_any.data(), n, y, z)]);
        row_any[static_cast<size_t>(z) * n + y] = static_cast<uint8_t>(flag);
        if (!flag) continue;
        // With no voxel set every voxel context is the empty-neighbourhood one.
        for (int x = 0; x < n; ++x) enc.EncodeBool(0, ctx.voxel[0]);
      }
    }
    occ.Bytes(enc.Finish());
    writer.AddChunk(kChunkOccupancy, occ.bytes());
  }
  for (int g = 0; g < 2; ++g) {
    for (int t = 0; t < 6; ++t) {
      if (h.ranks[g][t % 3] == 0) continue;
      const int dims[3] = {t < 3 ? cs.block : 1, cs.block, cs.block};
      int extent[3];
      SceneTensorExtent(h, g, t, extent);
      int grid[3], blocks = 1;
      for (int a = 0; a < 3; ++a) blocks *= grid[a] = (extent[a] + dims[a] - 1) / dims[a];
      CoefContexts ctx;
      const BlockShape shape{dims[0], dims[1], dims[2]};
      const Status init = cs.neighbour
                              ? ctx.Init(shape, CoefContextSet::kNeighbour, grid, size_t{1} << 31)
                              : ctx.Init(shape, CoefContextSet::kNarrow);
      if (!init.ok()) return {};
      RangeEncoder enc;
      std::vector<int32_t> q(static_cast<size_t>(dims[0]) * dims[1] * dims[2], 0);
      if (cs.blocks == 1) {
        q[ctx.scan.entries.back().raster] = 1;  // the last scan position: eob = V
      }
      for (int b = 0; b < blocks; ++b) EncodeCoefBlock(enc, ctx, q.data());
      ByteWriter c;
      c.U8(static_cast<uint8_t>(g));
      c.U8(static_cast<uint8_t>(t));
      c.U8(8);
      c.U8(static_cast<uint8_t>(cs.neighbour ? CoefContextSet::kNeighbour
                                             : CoefContextSet::kNarrow));
      for (int a = 0; a < 3; ++a) c.U8(static_cast<uint8_t>(dims[a]));
      c.U8(0);
      c.F32(1e-6f);
      c.Bytes(enc.Finish());
      writer.AddChunk(kChunkCoefficients, c.bytes());
    }
  }
  writer.AddChunk(kChunkMlpWeights, ZeroMlpChunk(h));
  if (cs.padding > 0) writer.AddChunk(kChunkMetadata, std::vector<uint8_t>(cs.padding, ' '));
  return writer.Finish();
}

}  // namespace costly
}  // namespace ecrf

#endif  // ECRF_CONFORMANCE_COSTLY_STREAMS_H_
