// Must-reject conformance streams (SPEC.md 7.7): each is refused with the error category named,
// as AV1's conformance suites carry invalid streams. Built with format/ only from a valid vector
// (scene_2d_blocks and its relatives) with one thing broken, or from the costly streams of
// conformance/costly_streams.h. Two kinds:
//   normative: every conforming decoder refuses the stream with this category (SPEC.md 1.3, 2, 6,
//   8); budget:    the reference decoder refuses it at its default budgets (SPEC.md 8,
//   informative);
//              a decoder with other budgets may accept it, and then must decode it exactly.
// Stage "decode" is ecrf_scene_decode; stage "render" is ecrf_scene_render (or check_render) of a
// stream that decodes.
#ifndef ECRF_CONFORMANCE_REJECT_VECTORS_H_
#define ECRF_CONFORMANCE_REJECT_VECTORS_H_

#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "conformance/costly_streams.h"
#include "conformance/scene_vectors.h"
#include "format/container.h"
#include "format/crc32.h"
#include "format/status.h"

namespace ecrf {
namespace conformance {

struct RejectVector {
  std::string name;   // file name without ".ecrf"
  const char* stage;  // "decode" or "render"
  int code;           // kErr* (the C API's ECRF_ERR_*)
  bool budget;        // refused by the reference decoder's default budgets, not by the format
  const char* why;
  std::vector<uint8_t> bytes;
};

namespace reject_internal {

using Chunks = std::vector<std::pair<uint32_t, std::vector<uint8_t>>>;

inline Chunks Split(const std::vector<uint8_t>& stream) {
  Chunks chunks;
  for (size_t pos = kFileHeaderBytes; pos + kChunkOverheadBytes <= stream.size();) {
    uint32_t type, length;
    std::memcpy(&type, stream.data() + pos, 4);
    std::memcpy(&length, stream.data() + pos + 4, 4);
    chunks.emplace_back(type, std::vector<uint8_t>(stream.begin() + long(pos) + 8,
                                                   stream.begin() + long(pos) + 8 + length));
    pos += kChunkOverheadBytes + length;
  }
  return chunks;
}

// The chunks again (DONE appended by the writer), with version_minor `minor`.
inline std::vector<uint8_t> Join(const Chunks& chunks, uint8_t minor) {
  ContainerWriter w(minor);
  for (const auto& [type, payload] : chunks) {
    if (type != kChunkDone) w.AddChunk(type, payload);
  }
  return w.Finish();
}

inline const SceneVector& Named(const char* name) {
  for (const SceneVector& v : SceneVectors()) {
    if (std::string(v.name) == name) return v;
  }
  return SceneVectors()[0];
}

inline size_t FirstChunk(const Chunks& chunks, uint32_t type) {
  for (size_t i = 0; i < chunks.size(); ++i) {
    if (chunks[i].first == type) return i;
  }
  return 0;
}

}  // namespace reject_internal

inline std::vector<RejectVector> RejectVectors() {
  using namespace reject_internal;  // NOLINT(google-build-using-namespace): this header's helpers
  const std::vector<uint8_t> base = BuildSceneVector(Named("scene_2d_blocks"));
  const Chunks chunks = Split(base);
  std::vector<RejectVector> v;
  auto add = [&v](const char* name, const char* stage, int code, bool budget, const char* why,
                  std::vector<uint8_t> bytes) {
    v.push_back({name, stage, code, budget, why, std::move(bytes)});
  };

  add("reject_truncated", "decode", kErrTruncated, false,
      "scene_2d_blocks cut in the middle of a chunk (2.2)",
      std::vector<uint8_t>(base.begin(), base.begin() + long(base.size() / 2)));
  {
    std::vector<uint8_t> b = base;
    b[kFileHeaderBytes + 8 + 20] ^= 0x01;  // a bit of the HEAD payload; its CRC now disagrees
    add("reject_crc_mismatch", "decode", kErrChecksum, false,
        "one bit of the HEAD payload flipped: the chunk's CRC-32 disagrees (2.4)", b);
  }
  {
    std::vector<uint8_t> b = base;
    b[0] = 'X';
    add("reject_signature", "decode", kErrCorrupt, false, "the signature is not \"ECRF\" (2.1)", b);
  }
  {
    std::vector<uint8_t> b = base;
    b[4] = 2;
    add("reject_version_major", "decode", kErrUnsupported, false, "version_major 2 (2.1)", b);
  }
  {
    Chunks c = chunks;
    c.insert(c.begin() + 1, {FourCC("ABCD"), std::vector<uint8_t>(4, 0)});
    add("reject_unknown_critical_chunk", "decode", kErrUnsupported, false,
        "a critical chunk type the decoder does not know, \"ABCD\" (2.3)", Join(c, base[5]));
  }
  {
    Chunks c = chunks;
    std::swap(c[0], c[1]);  // OCCU before HEAD
    add("reject_chunk_order", "decode", kErrCorrupt, false,
        "OCCU before HEAD: critical chunks out of order (6.1)", Join(c, base[5]));
  }
  {
    Chunks c = chunks;
    c[FirstChunk(c, FourCC("HEAD"))].second.pop_back();
    add("reject_head_length", "decode", kErrCorrupt, false,
        "a HEAD payload of 89 bytes instead of 90 (6.2)", Join(c, base[5]));
  }
  {
    const SceneHeader h = SceneVectorHeader(Named("scene_2d_blocks"));
    SceneHeader big = h;
    big.res[0] = 4097;
    ByteWriter head;
    WriteSceneHeader(big, SceneVectorVersionMinor(Named("scene_2d_blocks")), &head);
    Chunks c = chunks;
    c[FirstChunk(c, FourCC("HEAD"))].second = head.bytes();
    add("reject_grid_resolution", "decode", kErrLimit, false,
        "grid resolution 4097 on axis 0, beyond the limit of 4096 (8)", Join(c, base[5]));
  }
  {
    // An 8-bit COEF chunk whose only coded block holds a coefficient of magnitude 128.
    Chunks c = chunks;
    const size_t at = FirstChunk(c, FourCC("COEF"));
    std::vector<uint8_t>& payload = c[at].second;
    const int dims[3] = {payload[4], payload[5], payload[6]};
    SceneHeader h = SceneVectorHeader(Named("scene_2d_blocks"));
    int extent[3];
    SceneTensorExtent(h, payload[0], payload[1], extent);
    int blocks = 1;
    for (int a = 0; a < 3; ++a) blocks *= (extent[a] + dims[a] - 1) / dims[a];
    CoefContexts ctx;
    if (!ctx.Init(BlockShape{dims[0], dims[1], dims[2]}, CoefContextSet::kNarrow).ok()) return {};
    RangeEncoder enc;
    std::vector<int32_t> q(size_t(dims[0]) * dims[1] * dims[2], 0);
    for (int b = 0; b < blocks; ++b) {
      q[0] = b == 0 ? 128 : 0;
      EncodeCoefBlock(enc, ctx, q.data());
    }
    payload.resize(12);
    const std::vector<uint8_t> coded = enc.Finish();
    payload.insert(payload.end(), coded.begin(), coded.end());
    add("reject_coefficient_magnitude", "decode", kErrCorrupt, false,
        "an 8-bit COEF chunk with a coefficient of magnitude 128 > MaxAbs 127 (4.5)",
        Join(c, base[5]));
  }
  {
    const std::vector<uint8_t> q = BuildSceneVector(Named("scene_quantized_mlp"));
    add("reject_quantized_mlp_in_1_0", "decode", kErrCorrupt, false,
        "a quantized MLP (a 1.1 feature) in a stream labelled 1.0 (the version rule, 2.1)",
        Join(Split(q), 0));
  }
  {
    const std::vector<uint8_t> u = BuildSceneVector(Named("scene_unbounded"));
    add("reject_unbounded_in_1_1", "decode", kErrCorrupt, false,
        "the unbounded scene model (1.2) in a stream labelled 1.1 (2.1)", Join(Split(u), 1));
  }
  {
    const std::vector<uint8_t> w = BuildSceneVector(Named("scene_wide_contexts"));
    add("reject_wide_contexts_in_1_3", "decode", kErrCorrupt, false,
        "wide coefficient contexts (1.4) in a stream labelled 1.3 (2.1)", Join(Split(w), 3));
  }
  {
    const std::vector<uint8_t> n = BuildSceneVector(Named("scene_neighbour_contexts"));
    add("reject_neighbour_contexts_in_1_4", "decode", kErrCorrupt, false,
        "wide occupancy and neighbour coefficient contexts (1.5) in a stream labelled 1.4 (2.1)",
        Join(Split(n), 4));
  }
  {
    const std::vector<uint8_t> d = BuildSceneVector(Named("scene_deferred_head"));
    add("reject_deferred_head_in_1_5", "decode", kErrCorrupt, false,
        "the deferred head (1.6) in a stream labelled 1.5 (2.1)", Join(Split(d), 5));
    Chunks c = Split(d);
    for (auto& [type, payload] : c) {
      if (type == kChunkMlpWeights) payload[1] = kNumHeadKinds;
    }
    add("reject_unknown_head", "decode", kErrUnsupported, false,
        "an MLPW head of 2, unknown to this version (6.6)", Join(c, d[5]));
  }
  {
    const std::vector<uint8_t> d = BuildSceneVector(Named("scene_one_hidden_layer"));
    add("reject_one_hidden_layer_in_1_7", "decode", kErrCorrupt, false,
        "the MLP with one hidden layer (MLPW layers 1, 1.8) in a stream labelled 1.7 (2.1)",
        Join(Split(d), 7));
    Chunks c = Split(d);
    for (auto& [type, payload] : c) {
      if (type == kChunkMlpWeights) payload[2] = kMlpOneHiddenLayer + 1;
    }
    add("reject_unknown_mlp_layers", "decode", kErrUnsupported, false,
        "an MLPW layers byte of 2, unknown to this version (6.6)", Join(c, d[5]));
  }
  {
    // A 1.9 stream's HEAD carries a 91st byte; labelled 1.8 its HEAD is one byte too long.
    const std::vector<uint8_t> d = BuildSceneVector(Named("scene_relu_density"));
    add("reject_relu_density_in_1_8", "decode", kErrCorrupt, false,
        "ReLU density (the HEAD density_activation byte, 1.9) in a stream labelled 1.8: a HEAD "
        "payload of 91 bytes instead of 90 (2.1, 6.2)",
        Join(Split(d), 8));
    Chunks c = Split(d);
    for (auto& [type, payload] : c) {
      if (type == kChunkHead) payload[kSceneHeaderBytes] = kNumDensityActivations;
    }
    add("reject_unknown_density_activation", "decode", kErrUnsupported, false,
        "a HEAD density_activation of 2, unknown to this version (6.2)", Join(c, d[5]));
  }
  {
    const std::vector<uint8_t> d = BuildSceneVector(Named("scene_sh_deferred"));
    add("reject_sh_colour_in_1_6", "decode", kErrCorrupt, false,
        "the spherical-harmonics colour (HEAD hidden 0, 1.7) in a stream labelled 1.6 (2.1)",
        Join(Split(d), 6));
    // HEAD feature_dim (offset 82, u16) and viewdir_pe_freqs (85) of a hidden-0 stream.
    auto with_head_bytes = [&](size_t offset, std::vector<uint8_t> bytes) {
      Chunks c = Split(d);
      for (auto& [type, payload] : c) {
        if (type == kChunkHead) std::copy(bytes.begin(), bytes.end(), payload.begin() + offset);
      }
      return Join(c, d[5]);
    };
    add("reject_sh_feature_dim", "decode", kErrCorrupt, false,
        "hidden 0 with feature_dim 26, the coefficients of no degree (6.2)",
        with_head_bytes(82, {26, 0}));
    add("reject_sh_positional_encoding", "decode", kErrCorrupt, false,
        "hidden 0 with a view-direction encoding of 1 frequency (6.2)", with_head_bytes(85, {1}));
  }
  {
    const costly::CostlyScene cs = costly::EmptyFlaggedRows(512);
    add("reject_budget_occupancy_rows", "decode", kErrLimit, true,
        "OCCU 512^3 flagging every row and setting no voxel: 2^27 symbols from 3 KB, beyond the "
        "decode work budget (8)",
        costly::BuildCostlyStream(cs));
  }
  {
    const costly::CostlyScene cs = costly::FullLengthBlocks(16);
    add("reject_budget_full_length_blocks", "decode", kErrLimit, true,
        "6,144 blocks of 16^3 coded to their last position from 20 KB, beyond the decode work "
        "budget (8)",
        costly::BuildCostlyStream(cs));
  }
  {
    add("reject_budget_neighbour_contexts", "decode", kErrLimit, true,
        "2048^2 planes of rank 1 in 16^3 blocks with the neighbour contexts: clearing their "
        "contexts costs one unit per 16 bytes, beyond the decode work budget of the few hundred "
        "bytes that ask for it (8.1)",
        costly::BuildCostlyStream(costly::NeighbourContexts2048()));
  }
  {
    costly::CostlyScene cs;
    cs.res = 2048;
    cs.density_rank = 8;
    cs.appearance_rank = 8;
    cs.block = 16;
    add("reject_budget_memory", "decode", kErrLimit, true,
        "2048^3 grids of rank 8: 805 MB of float32 values (within the format's 2^28 values), "
        "beyond the memory budget (8)",
        costly::BuildCostlyStream(cs));
  }
  {
    const costly::CostlyScene cs = costly::WidestHead();
    add("reject_budget_render_work", "render", kErrLimit, true,
        "the widest head (F 256, H 1024, P 3072, 16 frequencies): 10.7 M multiply-adds per "
        "sample, beyond the work budget of one pixel (8)",
        costly::BuildCostlyStream(cs));
  }
  return v;
}

// "reject/expected.txt": one line per vector, "FILE STAGE CODE KIND", for checkers that parse no
// JSON (tests/decoder/conformance_checksums.cc).
inline std::string RejectExpectedText(const std::vector<RejectVector>& vectors) {
  std::string text;
  for (const RejectVector& r : vectors) {
    text += r.name + ".ecrf " + r.stage + " " + std::to_string(r.code) + " " +
            (r.budget ? "budget" : "normative") + "\n";
  }
  return text;
}

}  // namespace conformance
}  // namespace ecrf

#endif  // ECRF_CONFORMANCE_REJECT_VECTORS_H_
