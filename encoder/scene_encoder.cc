#include "encoder/scene_encoder.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <string>

#include "decoder/scene_decoder.h"
#include "encoder/coded_tensors.h"
#include "encoder/coef_quantizer.h"
#include "encoder/coef_rdoq.h"
#include "encoder/grid_dct.h"
#include "format/byte_io.h"
#include "format/coefficients/coef_coder.h"
#include "format/container.h"
#include "format/half_float.h"
#include "format/mlp_coder.h"
#include "format/ndc_frame.h"
#include "format/occupancy_coder.h"
#include "format/scene_header.h"

namespace ecrf {
namespace encoder {
namespace {

// Throws std::invalid_argument unless every array has the size the header gives it.
void CheckDescription(const SceneDescription& s) {
  const SceneHeader& h = s.header;
  for (int g = 0; g < 2; ++g) {
    for (int t = 0; t < 6; ++t) {
      int extent[3];
      SceneTensorExtent(h, g, t, extent);
      const size_t expected = size_t(extent[0]) * extent[1] * extent[2];
      if (s.tensors[g][t].size() != expected) {
        throw std::invalid_argument("EncodeScene: tensor " +
                                    std::string(RateTensorName(g * 6 + t)) + " holds " +
                                    std::to_string(s.tensors[g][t].size()) +
                                    " values, its header shape " + std::to_string(expected));
      }
    }
  }
  if (s.mlp_hidden_layers != 2 && (s.mlp_hidden_layers != 1 || h.hidden == 0)) {
    throw std::invalid_argument("EncodeScene: " + std::to_string(s.mlp_hidden_layers) +
                                " hidden layers (2, or 1 with a hidden width above 0)");
  }
  const MlpLayout mlp = MakeMlpLayout(h.feature_dim, h.total_rank(1), h.hidden, h.feature_pe_freqs,
                                      h.viewdir_pe_freqs, s.mlp_hidden_layers);
  if (s.head_params.size() != MlpParamCount(mlp)) {
    throw std::invalid_argument("EncodeScene: " + std::to_string(s.head_params.size()) +
                                " head parameters, the header's head has " +
                                std::to_string(MlpParamCount(mlp)));
  }
  if (s.mask) {
    const std::array<int, 3>& r = s.mask->res;
    if (r[0] < 2 || r[1] < 2 || r[2] < 2 ||
        s.mask->occupancy.size() != size_t(r[0]) * r[1] * r[2]) {
      throw std::invalid_argument("EncodeScene: the occupancy mask does not match its resolution");
    }
  }
}

// Keeps the components with keep[g][m][r] != 0 (and, for appearance, their basis columns).
SceneDescription DropComponents(const SceneDescription& in, const std::vector<uint8_t> keep[2][3]) {
  SceneDescription out = in;
  const SceneHeader& h = in.header;
  for (int g = 0; g < 2; ++g) {
    for (int m = 0; m < 3; ++m) {
      const int rank = h.ranks[g][m];
      std::vector<int> kept;
      for (int r = 0; r < rank; ++r) {
        if (keep[g][m][r]) kept.push_back(r);
      }
      const int nk = static_cast<int>(kept.size());
      out.header.ranks[g][m] = static_cast<uint16_t>(nk);
      const size_t plane_cells = size_t(h.res[kMatMode[m][0]]) * h.res[kMatMode[m][1]];
      const size_t line_cells = h.res[kVecMode[m]];
      for (int kind = 0; kind < 2; ++kind) {
        const size_t cells = kind == 0 ? plane_cells : line_cells;
        const std::vector<float>& src = in.tensors[g][kind * 3 + m];
        std::vector<float>& dst = out.tensors[g][kind * 3 + m];
        dst.assign(cells * nk, 0.f);
        for (size_t i = 0; i < cells; ++i) {
          for (int k = 0; k < nk; ++k) dst[i * nk + k] = src[i * rank + kept[k]];
        }
      }
    }
  }
  // Basis [F x P]: keep the columns of the kept appearance products.
  const int F = h.feature_dim;
  const int P = h.total_rank(1);
  std::vector<int> columns;
  for (int m = 0, offset = 0; m < 3; offset += h.ranks[1][m], ++m) {
    for (int r = 0; r < h.ranks[1][m]; ++r) {
      if (keep[1][m][r]) columns.push_back(offset + r);
    }
  }
  const size_t basis_size = size_t(F) * P;
  std::vector<float> params;
  params.reserve(in.head_params.size());
  for (int f = 0; f < F; ++f) {
    for (int col : columns) params.push_back(in.head_params[size_t(f) * P + col]);
  }
  params.insert(params.end(), in.head_params.begin() + static_cast<long>(basis_size),
                in.head_params.end());
  out.head_params = std::move(params);
  return out;
}

// The lowest minor version of the features used, wide contexts aside: 1.1 for the quantized MLP,
// 1.2 unbounded, 1.3 forward-facing, 1.6 deferred, 1.7 spherical harmonics, 1.8 one hidden layer,
// 1.9 ReLU density.
uint8_t FeatureVersionMinor(const SceneDescription& s, const EncodeOptions& o) {
  return std::max(
      {o.mlp_max_level > 0 ? kQuantizedMlpMinVersionMinor : uint8_t{0},
       kSceneModelMinVersionMinor[s.header.scene_model],
       kHeadKindMinVersionMinor[static_cast<int>(s.head)],
       s.header.hidden == 0 ? kShColourMinVersionMinor : uint8_t{0},
       s.mlp_hidden_layers == 1 ? kOneHiddenLayerMinVersionMinor : uint8_t{0},
       s.header.density_activation != 0 ? kDensityActivationMinVersionMinor : uint8_t{0}});
}

// The shortest of the codes of `sets` (in order; the first wins ties) whose minimum version the
// asked version allows: encode(set) codes the same data with one context set. The first set
// must be allowed in every version.
template <typename Set, typename Encode, typename MinVersion>
std::vector<uint8_t> ShortestCode(std::initializer_list<Set> sets, int max_version_minor,
                                  MinVersion min_version, Encode encode, Set* chosen) {
  std::vector<uint8_t> best;
  bool first = true;
  for (Set set : sets) {
    if (!first && max_version_minor < min_version(set)) continue;
    std::vector<uint8_t> code = encode(set);
    if (first || code.size() < best.size()) {
      best = std::move(code);
      *chosen = set;
    }
    first = false;
  }
  return best;
}

std::vector<uint8_t> CodeLevels(const std::vector<int32_t>& levels, const GridBlockLayout& layout,
                                CoefContextSet set) {
  CoefContexts contexts;
  const Status st = contexts.Init(BlockShape{layout.block[0], layout.block[1], layout.block[2]},
                                  set, layout.blocks, static_cast<size_t>(-1));
  if (!st.ok()) throw std::invalid_argument(st.message());
  RangeEncoder enc;
  const size_t volume = size_t(layout.block_volume());
  for (int b = 0; b < layout.num_blocks(); ++b)
    EncodeCoefBlock(enc, contexts, &levels[size_t(b) * volume]);
  return enc.Finish();
}

std::vector<uint8_t> EncodeCoefficients(const SceneDescription& s, int g, int t, float step,
                                        const EncodeOptions& o, EncodeReport* report) {
  const GridBlockLayout layout = CodedTensorLayout(s.header, g, t, o.blocks);
  std::vector<float> coeffs(layout.num_coeffs());
  ForwardBlocks(s.tensors[g][t].data(), layout, coeffs.data());
  const int32_t max_abs = MaxCoefficientLevel(o.coef_bits);
  const int volume = layout.block_volume();
  std::vector<int32_t> levels(coeffs.size(), 0);
  const int index = g * 6 + t;
  RdoqOptions rdoq;
  rdoq.set = CoefContextSet::kNarrow;
  rdoq.lambda = o.rdoq_lambda;
  rdoq.rounding_offset = o.rounding_offset;
  rdoq.max_abs = max_abs;
  // RDOQ decides with the costs of the richest context set the asked version allows.
  for (CoefContextSet set : {CoefContextSet::kWide, CoefContextSet::kNeighbour}) {
    if (o.max_version_minor >= CoefContextSetMinVersionMinor(set)) rdoq.set = set;
  }
  report->clipped_coefficients += RdoqLevels(coeffs.data(), layout, step, rdoq, levels.data());
  for (int b = 0; b < layout.num_blocks(); ++b) {
    const int32_t* q = &levels[size_t(b) * volume];
    report->tensor_zero_blocks[index] +=
        std::all_of(q, q + volume, [](int32_t v) { return v == 0; });
  }
  // Every context set the asked version allows codes the same levels; the chunk keeps the
  // shortest code, so no tensor ever grows over its size in an older version.
  CoefContextSet set = CoefContextSet::kNarrow;
  const std::vector<uint8_t> code = ShortestCode(
      {CoefContextSet::kNarrow, CoefContextSet::kWide, CoefContextSet::kNeighbour},
      o.max_version_minor, CoefContextSetMinVersionMinor,
      [&](CoefContextSet candidate) { return CodeLevels(levels, layout, candidate); }, &set);
  report->tensor_blocks[index] = size_t(layout.num_blocks());
  report->tensor_coeffs[index] = layout.num_coeffs();
  ByteWriter w;
  w.U8(uint8_t(g));
  w.U8(uint8_t(t));
  w.U8(uint8_t(o.coef_bits));
  w.U8(static_cast<uint8_t>(set));
  for (int a = 0; a < 3; ++a) w.U8(uint8_t(layout.block[a]));
  w.U8(0);
  w.F32(step);
  w.Bytes(code);
  return std::move(w.bytes());
}

// The shorter of the narrow and (where the asked version allows it) the wide code.
std::vector<uint8_t> EncodeOccupancyChunk(const OccupancyDescription& mask, int max_version_minor,
                                          OccupancyContextSet* set_out) {
  const int res[3] = {mask.res[0], mask.res[1], mask.res[2]};
  OccupancyContextSet set = OccupancyContextSet::kNarrow;
  const std::vector<uint8_t> code = ShortestCode(
      {OccupancyContextSet::kNarrow, OccupancyContextSet::kWide}, max_version_minor,
      [](OccupancyContextSet candidate) {
        return candidate == OccupancyContextSet::kWide ? kWideOccupancyContextsMinVersionMinor : 0;
      },
      [&](OccupancyContextSet candidate) {
        return EncodeOccupancy(mask.occupancy.data(), res, candidate);
      },
      &set);
  ByteWriter w;
  for (float v : mask.aabb_min) w.F32(v);
  for (float v : mask.aabb_max) w.F32(v);
  for (int r : mask.res) w.U16(uint16_t(r));
  w.U16(static_cast<uint16_t>(set));
  w.Bytes(code);
  *set_out = set;
  return std::move(w.bytes());
}

std::vector<uint8_t> EncodeMlpChunk(const SceneHeader& h, HeadKind head, int hidden_layers,
                                    const std::vector<float>& params, bool float32, int max_level) {
  ByteWriter w;
  w.U8(max_level > 0 ? kMlpPrecisionQuantized
       : float32     ? kMlpPrecisionFloat32
                     : kMlpPrecisionFloat16);
  w.U8(static_cast<uint8_t>(head));
  w.U8(hidden_layers == 1 ? kMlpOneHiddenLayer : kMlpTwoHiddenLayers);
  w.U8(0);
  if (max_level > 0) {
    const MlpLayout layout = MakeMlpLayout(h.feature_dim, h.total_rank(1), h.hidden,
                                           h.feature_pe_freqs, h.viewdir_pe_freqs, hidden_layers);
    w.Bytes(EncodeQuantizedMlp(layout, params.data(), max_level, nullptr));
    return std::move(w.bytes());
  }
  for (float v : params) {
    if (float32) {
      w.F32(v);
    } else {
      w.U16(FloatToHalf(v));
    }
  }
  return std::move(w.bytes());
}

std::vector<uint8_t> Assemble(const SceneDescription& s, const std::vector<float>& steps,
                              const EncodeOptions& o, EncodeReport* report) {
  *report = EncodeReport{};
  SceneHeader h = s.header;
  const uint8_t feature_minor = FeatureVersionMinor(s, o);
  if (feature_minor > o.max_version_minor) {
    throw std::invalid_argument(
        "this scene needs stream version 1." + std::to_string(feature_minor) + " (" +
        SceneModelName(static_cast<SceneModel>(h.scene_model)) + " model, " + HeadKindName(s.head) +
        " head, MLP levels " + std::to_string(o.mlp_max_level) + ", " +
        DensityActivationName(static_cast<DensityActivation>(h.density_activation)) +
        " density), above the asked 1." + std::to_string(o.max_version_minor));
  }
  std::vector<uint8_t> coef_chunks[2][6];
  uint8_t version_minor = feature_minor;
  for (int g = 0; g < 2; ++g) {
    for (int t = 0; t < 6; ++t) {
      if (h.ranks[g][t % 3] == 0) continue;
      coef_chunks[g][t] = EncodeCoefficients(s, g, t, steps[g * 6 + t], o, report);
      version_minor = std::max(
          version_minor,
          CoefContextSetMinVersionMinor(static_cast<CoefContextSet>(coef_chunks[g][t][3])));
    }
  }
  h.has_occupancy = (o.include_occupancy && s.mask.has_value()) ? 1 : 0;
  std::vector<uint8_t> occupancy_chunk;
  if (h.has_occupancy) {
    OccupancyContextSet set = OccupancyContextSet::kNarrow;
    occupancy_chunk = EncodeOccupancyChunk(*s.mask, o.max_version_minor, &set);
    if (set == OccupancyContextSet::kWide) {
      version_minor = std::max(version_minor, kWideOccupancyContextsMinVersionMinor);
    }
  }
  // The lowest version of the features used: 1.4 for wide coefficient contexts, 1.5 for
  // neighbour coefficient contexts and wide occupancy contexts. Final here: HEAD's length
  // depends on it.
  ContainerWriter writer(version_minor);
  ByteWriter head;
  WriteSceneHeader(h, version_minor, &head);
  writer.AddChunk(kChunkHead, head.bytes());
  report->head_bytes = head.size();
  size_t chunks = 2 + h.has_occupancy;  // HEAD, DONE, OCCU
  if (h.scene_model == static_cast<uint8_t>(SceneModel::kForward)) {
    ByteWriter ndc;
    WriteNdcFrame(s.ndc, &ndc);
    writer.AddChunk(kChunkNdcFrame, ndc.bytes());
    report->head_bytes += ndc.size();
    ++chunks;
  }
  if (h.has_occupancy) {
    writer.AddChunk(kChunkOccupancy, occupancy_chunk);
    report->occupancy_bytes = occupancy_chunk.size();
  }
  for (int g = 0; g < 2; ++g) {
    for (int t = 0; t < 6; ++t) {
      report->steps[g * 6 + t] = steps[g * 6 + t];
      if (h.ranks[g][t % 3] == 0) continue;
      const std::vector<uint8_t>& coef = coef_chunks[g][t];
      writer.AddChunk(kChunkCoefficients, coef);
      report->tensor_bytes[g * 6 + t] = coef.size();
      ++chunks;
    }
  }
  const std::vector<uint8_t> mlp =
      EncodeMlpChunk(h, s.head, s.mlp_hidden_layers, s.head_params, o.mlp_float32, o.mlp_max_level);
  writer.AddChunk(kChunkMlpWeights, mlp);
  report->mlp_bytes = mlp.size();
  ++chunks;
  if (!o.metadata_json.empty()) {
    writer.AddChunk(kChunkMetadata, reinterpret_cast<const uint8_t*>(o.metadata_json.data()),
                    o.metadata_json.size());
    report->metadata_bytes = o.metadata_json.size();
    ++chunks;
  }
  std::vector<uint8_t> bytes = writer.Finish();
  report->total_bytes = bytes.size();
  report->container_bytes = kFileHeaderBytes + chunks * kChunkOverheadBytes;
  for (int g = 0; g < 2; ++g) {
    for (int m = 0; m < 3; ++m) report->ranks_out[g][m] = h.ranks[g][m];
  }
  return bytes;
}

void Decode(const std::vector<uint8_t>& bytes, dec::SceneField* field) {
  dec::DecodeOptions options;
  options.max_memory_bytes = ~uint64_t{0};  // our own stream: no budget
  const Status s = dec::DecodeScene(bytes.data(), bytes.size(), options, field, nullptr);
  if (!s.ok()) {
    throw std::runtime_error(std::string("encoder self-check: the stream does not decode: ") +
                             s.message());
  }
}

// A component is dead when its decoded plane or its decoded line is zero everywhere.
bool DecodedSliceIsZero(const float* data, size_t cells, int rank, int r) {
  for (size_t i = 0; i < cells; ++i) {
    if (data[i * rank + r] != 0.f) return false;
  }
  return true;
}

}  // namespace

std::vector<uint8_t> EncodeScene(const SceneDescription& scene, const EncodeOptions& o,
                                 EncodeReport* report_out) {
  CheckDescription(scene);
  if (o.coef_bits != 8 && o.coef_bits != 16) {
    throw std::invalid_argument("coefficient bits must be 8 or 16, not " +
                                std::to_string(o.coef_bits));
  }
  if (!(o.rounding_offset > 0.f && o.rounding_offset <= 0.5f)) {
    throw std::invalid_argument("rounding offset " + std::to_string(o.rounding_offset) +
                                " outside (0, 0.5]");
  }
  if (!(o.rdoq_lambda >= 0.f && o.rdoq_lambda <= kMaxRdoqLambda)) {
    throw std::invalid_argument("RDOQ lambda " + std::to_string(o.rdoq_lambda) + " outside [0, " +
                                std::to_string(kMaxRdoqLambda) + "]");
  }
  if (!o.steps.empty() && o.steps.size() != 12) {
    throw std::invalid_argument("EncodeScene: expected 12 quantization steps, got " +
                                std::to_string(o.steps.size()));
  }
  std::vector<float> steps =
      o.steps.empty() ? ChooseQuantSteps(scene, o.blocks, o.coef_bits) : o.steps;
  for (float& s : steps) {
    if (!(s > 0.f && s <= 0x1p64f)) {
      throw std::invalid_argument("quantization step " + std::to_string(s) + " outside (0, 2^64]");
    }
    // The stream's smallest step; a tensor this small codes as zeros either way.
    s = std::max(s, 0x1p-64f);
  }
  EncodeReport report;
  std::vector<uint8_t> bytes = Assemble(scene, steps, o, &report);
  dec::SceneField decoded;
  Decode(bytes, &decoded);

  if (o.drop_zero_components) {
    std::vector<uint8_t> keep[2][3];
    bool any_dropped = false;
    const dec::VmGrid* grids[2] = {&decoded.density, &decoded.appearance};
    for (int g = 0; g < 2; ++g) {
      for (int m = 0; m < 3; ++m) {
        const dec::VmGrid& dg = *grids[g];
        const int rank = dg.ranks[m];
        keep[g][m].assign(size_t(rank), 1);
        const size_t plane_cells = rank ? dg.plane_count(m) / rank : 0;
        const size_t line_cells = rank ? dg.line_count(m) / rank : 0;
        for (int r = 0; r < rank; ++r) {
          if (DecodedSliceIsZero(dg.plane_f32[m].data(), plane_cells, rank, r) ||
              DecodedSliceIsZero(dg.line_f32[m].data(), line_cells, rank, r)) {
            keep[g][m][r] = 0;
            any_dropped = true;
          }
        }
      }
    }
    // The MLP needs at least one appearance product.
    if (any_dropped) {
      bool app_left = false;
      for (int m = 0; m < 3; ++m) {
        for (uint8_t k : keep[1][m]) app_left |= k != 0;
      }
      for (int m = 0; m < 3 && !app_left; ++m) {
        if (!keep[1][m].empty()) {
          keep[1][m][0] = 1;
          app_left = true;
        }
      }
      const SceneDescription reduced = DropComponents(scene, keep);
      bytes = Assemble(reduced, steps, o, &report);
      Decode(bytes, &decoded);
    }
  }
  for (int g = 0; g < 2; ++g) {
    for (int m = 0; m < 3; ++m) report.ranks_in[g][m] = scene.header.ranks[g][m];
  }
  if (report_out) *report_out = report;
  return bytes;
}

}  // namespace encoder
}  // namespace ecrf
