#include "decoder/scene_decoder.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "decoder/field_sampler.h"
#include "format/byte_io.h"
#include "format/coefficients/block_shape.h"
#include "format/coefficients/coef_coder.h"
#include "format/coefficients/int_idct.h"
#include "format/container.h"
#include "format/half_float.h"
#include "format/mlp_coder.h"
#include "format/ndc_frame.h"
#include "format/occupancy_coder.h"

namespace ecrf {
namespace dec {
namespace {

// DecodeOptions::max_memory_bytes, spent chunk by chunk before each allocation.
class MemoryBudget {
 public:
  explicit MemoryBudget(uint64_t total) : total_(total), left_(total) {}
  Status Take(uint64_t bytes, const char* what) {
    ECRF_CHECK_OR_RETURN(
        bytes <= left_, kErrLimit,
        "%s need %llu bytes, more than the %llu left of this decoder's memory budget of "
        "%llu bytes (DecodeOptions::max_memory_bytes; ecrf --max-memory-mb)",
        what, static_cast<unsigned long long>(bytes), static_cast<unsigned long long>(left_),
        static_cast<unsigned long long>(total_));
    left_ -= bytes;
    return Status::Ok();
  }
  // Returns memory taken for the length of one chunk (at most what was taken).
  void Give(uint64_t bytes) { left_ = bytes < total_ - left_ ? left_ + bytes : total_; }
  uint64_t spent() const { return total_ - left_; }

 private:
  uint64_t total_, left_;
};

// DecodeOptions::work_per_byte: the work a stream may cost, spent as it is decoded.
class WorkBudget {
 public:
  WorkBudget(uint64_t base, uint64_t per_byte, size_t stream_bytes)
      : base_(base), per_byte_(per_byte) {
    const uint64_t bytes = stream_bytes;
    total_ = per_byte == 0 || base > ~uint64_t{0} / 2 || bytes > (~uint64_t{0} / 2) / per_byte
                 ? ~uint64_t{0}
                 : base + per_byte * bytes;
    left_ = total_;
    bytes_ = bytes;
  }
  bool Take(uint64_t units) {
    if (units > left_) return false;
    left_ -= units;
    return true;
  }
  uint64_t* left() { return &left_; }
  uint64_t spent() const { return total_ - left_; }
  uint64_t total() const { return total_; }
  Status Refuse(const char* where) const {
    return Status::Error(
        kErrLimit,
        "%s: decoding costs more than this stream's decode budget of %llu units "
        "(%llu + %llu per byte of its %llu bytes; DecodeOptions::work_per_byte, "
        "ecrf --decode-budget N, 0 for no limit)",
        where, static_cast<unsigned long long>(total_), static_cast<unsigned long long>(base_),
        static_cast<unsigned long long>(per_byte_), static_cast<unsigned long long>(bytes_));
  }

 private:
  uint64_t base_, per_byte_, total_, left_, bytes_;
};

// Decode work of a coded block: its coefficients' symbols, and its inverse DCT, measured at about
// 16 multiply-adds of the IDCT per symbol's time (`ecrf bench idct`, `ecrf bench coder`).
uint64_t CodedBlockWork(const int dims[3], int eob) {
  const uint64_t volume = static_cast<uint64_t>(dims[0]) * dims[1] * dims[2];
  return static_cast<uint64_t>(eob) +
         volume * static_cast<uint64_t>(dims[0] + dims[1] + dims[2]) / 16;
}

const char* const kGridNames[kNumSceneGrids] = {"density", "appearance"};
const char* const kTensorNames[kTensorsPerSceneGrid] = {"plane 0", "plane 1", "plane 2",
                                                        "line 0",  "line 1",  "line 2"};

// Where tensor t of a grid lives and the strides of its three block axes (SPEC.md 6.4).
struct TensorTarget {
  float* data = nullptr;
  int extent[3] = {1, 1, 1};
  size_t stride[3] = {0, 0, 0};
};

TensorTarget TargetOf(VmGrid* grid, const SceneHeader& h, int g, int t) {
  TensorTarget target;
  SceneTensorExtent(h, g, t, target.extent);
  const int m = t % 3;
  const size_t rank = static_cast<size_t>(grid->ranks[m]);
  if (t < 3) {
    target.data = grid->plane_f32[m].data();
    target.stride[0] = 1;                                                      // channel
    target.stride[1] = static_cast<size_t>(grid->res[kMatMode[m][0]]) * rank;  // row (v)
    target.stride[2] = rank;                                                   // column (u)
  } else {
    target.data = grid->line_f32[m].data();
    target.stride[0] = 0;
    target.stride[1] = 1;     // channel
    target.stride[2] = rank;  // position along w
  }
  return target;
}

// A COEF chunk's contexts (SPEC.md 8.1). The neighbour set keeps the capped levels of one block
// per (b1, b2) column while the chunk decodes (about a quarter of a channel block's float32
// bytes, more where the block pads the tensor): its memory is charged for the chunk, and
// allocating and clearing it one unit per 16 bytes (about 8 ns a unit, as the other charges:
// `ecrf bench budgets`, neighbour_contexts_2048). 582 bytes of stream cleared 400 MB before.
Status InitChunkContexts(const BlockShape& shape, CoefContextSet set, const int blocks[3],
                         MemoryBudget* budget, WorkBudget* work, CoefContexts* contexts) {
  const uint64_t bytes = set == CoefContextSet::kNeighbour ? NeighbourBytes(shape, blocks) : 0;
  ECRF_RETURN_IF_ERROR(budget->Take(bytes, "COEF: the neighbour contexts"));
  if (!work->Take(bytes / 16)) return work->Refuse("COEF: the neighbour contexts");
  ECRF_RETURN_IF_ERROR(contexts->Init(shape, set, blocks, static_cast<size_t>(bytes)));
  budget->Give(bytes);  // nothing else is charged while the chunk decodes
  return Status::Ok();
}

Status DecodeCoefficientChunk(const ChunkView& chunk, const SceneHeader& h, int g, int t,
                              int version_minor, MemoryBudget* budget, WorkBudget* work,
                              VmGrid* grid, TensorChunkInfo* info) {
  ByteReader r(chunk.data, chunk.size);
  uint8_t grid_index = 0, tensor_index = 0, coef_bits = 0, contexts_byte = 0, reserved1 = 0;
  uint8_t block[3] = {0, 0, 0};
  float step = 0.f;
  ECRF_RETURN_IF_ERROR(r.ReadU8(&grid_index, "COEF grid"));
  ECRF_RETURN_IF_ERROR(r.ReadU8(&tensor_index, "COEF tensor"));
  ECRF_RETURN_IF_ERROR(r.ReadU8(&coef_bits, "COEF coef_bits"));
  ECRF_RETURN_IF_ERROR(r.ReadU8(&contexts_byte, "COEF contexts"));
  for (uint8_t& b : block) ECRF_RETURN_IF_ERROR(r.ReadU8(&b, "COEF block shape"));
  ECRF_RETURN_IF_ERROR(r.ReadU8(&reserved1, "COEF reserved"));
  ECRF_RETURN_IF_ERROR(r.ReadF32(&step, "COEF step"));
  ECRF_CHECK_OR_RETURN(grid_index == g && tensor_index == t, kErrCorrupt,
                       "COEF chunk at offset %zu is for grid %u tensor %u, expected %s %s",
                       chunk.offset, grid_index, tensor_index, kGridNames[g], kTensorNames[t]);
  ECRF_CHECK_OR_RETURN(reserved1 == 0, kErrCorrupt, "COEF %s %s: reserved byte must be 0",
                       kGridNames[g], kTensorNames[t]);
  // Values above the known sets are unsupported; a known set of a later minor version than
  // the stream's is corrupt (the version rule, SPEC.md 2.1: before 1.4 the byte was reserved, 0).
  ECRF_CHECK_OR_RETURN(contexts_byte <= kMaxCoefContextSet, kErrUnsupported,
                       "COEF %s %s: unknown coefficient context set %u", kGridNames[g],
                       kTensorNames[t], contexts_byte);
  const uint8_t contexts_minor =
      CoefContextSetMinVersionMinor(static_cast<CoefContextSet>(contexts_byte));
  ECRF_CHECK_OR_RETURN(version_minor >= contexts_minor, kErrCorrupt,
                       "COEF %s %s: contexts %u needs version_minor >= %d, the stream says %d "
                       "(SPEC.md 2.1)",
                       kGridNames[g], kTensorNames[t], contexts_byte, contexts_minor,
                       version_minor);
  const CoefContextSet context_set = static_cast<CoefContextSet>(contexts_byte);
  ECRF_CHECK_OR_RETURN(coef_bits == 8 || coef_bits == 16, kErrUnsupported,
                       "COEF %s %s: coef_bits %u (8 or 16)", kGridNames[g], kTensorNames[t],
                       coef_bits);
  const int dims[3] = {block[0], block[1], block[2]};
  ECRF_CHECK_OR_RETURN(IsValidBlockShape(dims) && (t < 3 || dims[0] == 1), kErrCorrupt,
                       "COEF %s %s: invalid block shape %dx%dx%d", kGridNames[g], kTensorNames[t],
                       dims[0], dims[1], dims[2]);
  // Steps in [2^-64, 2^64] keep step * 2^-P a normal float32, so the scale is exact.
  ECRF_CHECK_OR_RETURN(std::isfinite(step) && step >= 0x1p-64f && step <= 0x1p64f, kErrCorrupt,
                       "COEF %s %s: quantization step %g outside [2^-64, 2^64]", kGridNames[g],
                       kTensorNames[t], static_cast<double>(step));
  const int frac_bits = IdctOutputFracBits(coef_bits);
  const float scale = std::ldexp(step, -frac_bits);
  const int32_t max_abs = coef_bits == 16 ? 32767 : 127;

  const TensorTarget target = TargetOf(grid, h, g, t);
  int blocks[3];
  for (int a = 0; a < 3; ++a) blocks[a] = (target.extent[a] + dims[a] - 1) / dims[a];
  info->present = true;
  info->coef_bits = coef_bits;
  info->contexts = contexts_byte;
  for (int a = 0; a < 3; ++a) info->block[a] = dims[a];
  info->step = step;
  info->payload_bytes = chunk.size;
  info->blocks = static_cast<uint32_t>(blocks[0]) * blocks[1] * blocks[2];
  info->coded_blocks = 0;

  CoefContexts contexts;
  ECRF_RETURN_IF_ERROR(InitChunkContexts(BlockShape{dims[0], dims[1], dims[2]}, context_set, blocks,
                                         budget, work, &contexts));
  HeapArray<int32_t> block_buffers;
  ECRF_RETURN_IF_ERROR(block_buffers.Allocate(2 * static_cast<size_t>(kMaxBlockVolume)));
  int32_t* coeffs = block_buffers.data();
  int32_t* samples = block_buffers.data() + kMaxBlockVolume;
  RangeDecoder decoder(r.current(), r.remaining());
  for (int b0 = 0; b0 < blocks[0]; ++b0) {
    for (int b1 = 0; b1 < blocks[1]; ++b1) {
      for (int b2 = 0; b2 < blocks[2]; ++b2) {
        int eob = 0;
        const Status s = DecodeCoefBlock(decoder, contexts, max_abs, coeffs, &eob);
        if (!s.ok()) {
          return Status::Error(s.code(), "COEF %s %s, block (%d, %d, %d): %s", kGridNames[g],
                               kTensorNames[t], b0, b1, b2, s.message());
        }
        // A block costs its `coded` symbol; a coded one its coefficients and inverse DCT.
        if (!work->Take(eob == 0 ? 1 : CodedBlockWork(dims, eob))) {
          char where[96];
          std::snprintf(where, sizeof(where), "COEF %s %s, block (%d, %d, %d)", kGridNames[g],
                        kTensorNames[t], b0, b1, b2);
          return work->Refuse(where);
        }
        if (eob == 0) continue;  // the grid is zero-initialised
        ++info->coded_blocks;
        InverseDctInt(coeffs, dims, coef_bits, samples);
        // Crop: only positions inside the tensor are stored (SPEC.md 6.4).
        const int n0 = std::min(dims[0], target.extent[0] - b0 * dims[0]);
        const int n1 = std::min(dims[1], target.extent[1] - b1 * dims[1]);
        const int n2 = std::min(dims[2], target.extent[2] - b2 * dims[2]);
        for (int i0 = 0; i0 < n0; ++i0) {
          for (int i1 = 0; i1 < n1; ++i1) {
            const int32_t* src = samples + (i0 * dims[1] + i1) * dims[2];
            float* dst = target.data + (static_cast<size_t>(b0) * dims[0] + i0) * target.stride[0] +
                         (static_cast<size_t>(b1) * dims[1] + i1) * target.stride[1] +
                         static_cast<size_t>(b2) * dims[2] * target.stride[2];
            for (int i2 = 0; i2 < n2; ++i2) {
              dst[static_cast<size_t>(i2) * target.stride[2]] = static_cast<float>(src[i2]) * scale;
            }
          }
        }
      }
    }
  }
  const Status s = decoder.Finish();
  if (!s.ok()) {
    return Status::Error(s.code(), "COEF %s %s: %s", kGridNames[g], kTensorNames[t], s.message());
  }
  return Status::Ok();
}

Status DecodeOccupancyChunk(const ChunkView& chunk, int version_minor, MemoryBudget* budget,
                            WorkBudget* work, SceneField* scene, SceneInfo* info) {
  ByteReader r(chunk.data, chunk.size);
  float lo[3] = {0.f, 0.f, 0.f}, hi[3] = {0.f, 0.f, 0.f};
  uint16_t res16[3] = {0, 0, 0}, contexts = 0;
  for (float& v : lo) ECRF_RETURN_IF_ERROR(r.ReadF32(&v, "OCCU aabb_min"));
  for (float& v : hi) ECRF_RETURN_IF_ERROR(r.ReadF32(&v, "OCCU aabb_max"));
  for (uint16_t& v : res16) ECRF_RETURN_IF_ERROR(r.ReadU16(&v, "OCCU resolution"));
  ECRF_RETURN_IF_ERROR(r.ReadU16(&contexts, "OCCU contexts"));
  // The version rule (SPEC.md 2.1): before 1.5 the field was reserved (0).
  ECRF_CHECK_OR_RETURN(contexts <= kMaxOccupancyContextSet, kErrUnsupported,
                       "OCCU: unknown occupancy context set %u", contexts);
  ECRF_CHECK_OR_RETURN(contexts == 0 || version_minor >= kWideOccupancyContextsMinVersionMinor,
                       kErrCorrupt,
                       "OCCU: contexts %u needs version_minor >= %d, the stream says %d "
                       "(SPEC.md 2.1; the field was reserved, 0, before 1.5)",
                       contexts, kWideOccupancyContextsMinVersionMinor, version_minor);
  int res[3] = {0, 0, 0};
  uint64_t voxels = 1;
  for (int a = 0; a < 3; ++a) {
    ECRF_CHECK_OR_RETURN(std::isfinite(lo[a]) && std::isfinite(hi[a]) && hi[a] > lo[a] &&
                             std::isfinite(hi[a] - lo[a]),
                         kErrCorrupt, "OCCU: empty or non-finite box on axis %d", a);
    ECRF_CHECK_OR_RETURN(res16[a] >= 2 && res16[a] <= kMaxSceneGridRes, kErrLimit,
                         "OCCU: resolution %u on axis %d is outside [2, %d]", res16[a], a,
                         kMaxSceneGridRes);
    res[a] = res16[a];
    voxels *= res16[a];
  }
  ECRF_CHECK_OR_RETURN(voxels <= kMaxOccupancyVoxels, kErrLimit,
                       "OCCU: %llu voxels exceed the limit of %llu",
                       static_cast<unsigned long long>(voxels),
                       static_cast<unsigned long long>(kMaxOccupancyVoxels));
  // The bits, plus one byte per 4^3 and per 16^3 cells for the acceleration levels.
  ECRF_RETURN_IF_ERROR(
      budget->Take((voxels + 7) / 8 + voxels / 64 + voxels / 4096 + 2, "OCCU: the occupancy mask"));
  // Clearing the mask and building its acceleration levels: one unit per 64 voxels.
  if (!work->Take(voxels / 64)) return work->Refuse("OCCU");
  ECRF_RETURN_IF_ERROR(scene->mask.Init(lo, hi, res));
  const Status decoded =
      DecodeOccupancy(r.current(), r.remaining(), res, static_cast<OccupancyContextSet>(contexts),
                      scene->mask.bits(), work->left());
  if (decoded.code() == kErrLimit) return work->Refuse(decoded.message());
  ECRF_RETURN_IF_ERROR(decoded);
  ECRF_RETURN_IF_ERROR(scene->mask.BuildAcceleration());
  scene->has_mask = true;
  info->occupancy_bytes = chunk.size;
  for (int a = 0; a < 3; ++a) info->occupancy_res[a] = res[a];
  info->occupancy_contexts = static_cast<uint8_t>(contexts);
  info->occupied_voxels = scene->mask.occupied_count();
  return Status::Ok();
}

Status DecodeMlpChunk(const ChunkView& chunk, const SceneHeader& h, MemoryBudget* budget,
                      WorkBudget* work, int version_minor, SceneField* scene, SceneInfo* info) {
  ByteReader r(chunk.data, chunk.size);
  MlpChunkHeader mh;
  ECRF_RETURN_IF_ERROR(ReadMlpChunkHeader(&r, version_minor, h.hidden, &mh));
  const uint8_t precision = mh.precision, head = mh.head;
  scene->head = static_cast<HeadKind>(head);
  MlpConfig config;
  config.num_products = h.total_rank(1);
  config.feature_dim = h.feature_dim;
  config.feature_pe_freqs = h.feature_pe_freqs;
  config.viewdir_pe_freqs = h.viewdir_pe_freqs;
  config.hidden = h.hidden;
  config.hidden_layers = MlpHiddenLayers(mh.layers);
  const MlpLayout layout =
      MakeMlpLayout(h.feature_dim, config.num_products, h.hidden, h.feature_pe_freqs,
                    h.viewdir_pe_freqs, config.hidden_layers);
  {
    // The decoded parameters and the renderer's padded, transposed copy (at most 2x with padding).
    // NumParams of 6.6: under 2^24 within the header's limits.
    const uint64_t count = MlpParamCount(layout);
    ECRF_RETURN_IF_ERROR(budget->Take(count * 4 * 3, "MLPW: the MLP parameters"));
    // A quantized weight is at least one symbol; binary16 and binary32 ones are read in bulk.
    if (!work->Take(precision == kMlpPrecisionQuantized ? count : count / 8)) {
      return work->Refuse("MLPW");
    }
  }
  ECRF_RETURN_IF_ERROR(scene->mlp.Init(config));
  const size_t count = scene->mlp.num_params();
  HeapArray<float> params;
  ECRF_RETURN_IF_ERROR(params.Allocate(count));
  if (precision == kMlpPrecisionQuantized) {
    const Status q = DecodeQuantizedMlp(layout, r.current(), r.remaining(), params.data());
    if (!q.ok()) return Status::Error(q.code(), "MLPW: %s", q.message());
  } else {
    const size_t value_bytes = precision == kMlpPrecisionFloat16 ? 2 : 4;
    ECRF_CHECK_OR_RETURN(r.remaining() / value_bytes == count && r.remaining() % value_bytes == 0,
                         kErrCorrupt,
                         "MLPW: %zu bytes of weights, expected %zu values of %zu bytes",
                         r.remaining(), count, value_bytes);
    const uint8_t* p = r.current();
    for (size_t i = 0; i < count; ++i, p += value_bytes) {
      if (precision == kMlpPrecisionFloat16) {
        params[i] = HalfToFloat(static_cast<uint16_t>(p[0] | (p[1] << 8)));
      } else {
        const uint32_t u =
            uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
        std::memcpy(&params[i], &u, 4);
      }
    }
  }
  const Status s = scene->mlp.SetParams(params.data(), count);
  if (!s.ok()) return Status::Error(kErrCorrupt, "MLPW: %s", s.message());
  info->mlp_bytes = chunk.size;
  info->mlp_precision = precision;
  info->head = static_cast<HeadKind>(head);
  info->mlp_hidden_layers = config.hidden_layers;
  info->mlp_precision_bits = precision == kMlpPrecisionFloat16   ? 16
                             : precision == kMlpPrecisionFloat32 ? 32
                                                                 : 0;
  return Status::Ok();
}

void ApplyHeader(const SceneHeader& h, SceneField* scene) {
  scene->scene_model = static_cast<SceneModel>(h.scene_model);
  scene->head = HeadKind::kPerSample;  // until MLPW says otherwise
  for (int a = 0; a < 3; ++a) {
    scene->aabb_min[a] = h.aabb_min[a];
    scene->aabb_max[a] = h.aabb_max[a];
    scene->res[a] = h.res[a];
  }
  scene->density_shift = h.density_shift;
  scene->density_activation = static_cast<DensityActivation>(h.density_activation);
  scene->distance_scale = h.distance_scale;
  scene->step_size = h.step_size;
  scene->n_samples = static_cast<int>(h.num_samples);
  scene->weight_threshold = h.weight_threshold;
  scene->near_far[0] = h.near_far[0];
  scene->near_far[1] = h.near_far[1];
  for (int c = 0; c < 3; ++c) scene->background[c] = h.background[c];
  scene->has_mask = false;
}

// The critical chunks in the only order a stream may have them (SPEC.md 6.1).
enum class Expect { kHead, kNdcFrame, kOccupancy, kCoefficients, kMlp, kDone };

const char* ExpectedChunkName(Expect expect) {
  return expect == Expect::kHead           ? "HEAD"
         : expect == Expect::kNdcFrame     ? "NDCP"
         : expect == Expect::kOccupancy    ? "OCCU"
         : expect == Expect::kCoefficients ? "COEF"
                                           : "MLPW";
}

// Where a stream is in the order of its critical chunks.
struct ChunkOrder {
  Expect expect = Expect::kHead;
  int next_tensor = 0;  // g * 6 + t of the next COEF chunk

  // What follows HEAD (but a forward-facing scene's NDCP) and NDCP: OCCU when the scene has an
  // occupancy mask, else the first tensor.
  void ExpectOccupancyOrTensor(const SceneHeader& h) {
    if (h.has_occupancy) {
      expect = Expect::kOccupancy;
    } else {
      AdvanceTensor(h);
    }
  }
  // Skips the tensors of rank 0 (they have no COEF chunk); after the last tensor, MLPW.
  void AdvanceTensor(const SceneHeader& h) {
    while (next_tensor < kNumSceneGrids * kTensorsPerSceneGrid &&
           SceneTensorRank(h, next_tensor / kTensorsPerSceneGrid,
                           next_tensor % kTensorsPerSceneGrid) == 0) {
      ++next_tensor;
    }
    expect =
        next_tensor < kNumSceneGrids * kTensorsPerSceneGrid ? Expect::kCoefficients : Expect::kMlp;
  }
};

// The ancillary chunks are skipped; the metadata is kept (pointing into the stream).
void RecordAncillaryChunk(const ChunkView& chunk, SceneInfo& info) {
  if (chunk.type == kChunkMetadata) {
    info.metadata = chunk.data;
    info.metadata_size = chunk.size;
    info.metadata_bytes += chunk.size;
  } else {
    info.other_ancillary_bytes += chunk.size;
  }
}

// HEAD: the header, checked against the stream's version, and the grids it describes allocated.
Status DecodeHeadChunk(const ChunkView& chunk, const DecodeOptions& options, MemoryBudget& budget,
                       SceneField* scene, SceneInfo& info) {
  SceneHeader& h = info.header;
  ECRF_RETURN_IF_ERROR(ParseSceneHeader(chunk.data, chunk.size, info.version_minor, &h));
  // The version rule (SPEC.md 2.1): a feature of a later minor version than the stream's.
  // (ParseSceneHeader has refused unknown scene models.)
  const int model_minor = kSceneModelMinVersionMinor[h.scene_model];
  ECRF_CHECK_OR_RETURN(info.version_minor >= model_minor, kErrCorrupt,
                       "HEAD: scene_model %u needs version_minor >= %d, the stream says %u "
                       "(SPEC.md 2.1)",
                       h.scene_model, model_minor, info.version_minor);
  ECRF_CHECK_OR_RETURN(h.hidden != 0 || info.version_minor >= kShColourMinVersionMinor, kErrCorrupt,
                       "HEAD: hidden 0 (spherical-harmonics colour) needs version_minor >= %d, "
                       "the stream says %u (SPEC.md 2.1)",
                       kShColourMinVersionMinor, info.version_minor);
  // The 16-bit conversion holds both copies for a moment.
  const uint64_t grid_bytes = SceneGridValues(h) * (options.storage == GridStorage::kInt16 ? 6 : 4);
  ECRF_RETURN_IF_ERROR(budget.Take(grid_bytes, "HEAD: the grids"));
  info.head_bytes = chunk.size;
  ApplyHeader(h, scene);
  int res[3], ranks[kNumSceneGrids][3];
  for (int a = 0; a < 3; ++a) {
    res[a] = h.res[a];
    for (int g = 0; g < kNumSceneGrids; ++g) ranks[g][a] = h.ranks[g][a];
  }
  ECRF_RETURN_IF_ERROR(scene->density.Allocate(res, ranks[0], GridStorage::kFloat32));
  return scene->appearance.Allocate(res, ranks[1], GridStorage::kFloat32);
}

// A critical chunk: decoded when it is the one the order expects, else refused (out of order, or
// unknown).
Status DecodeCriticalChunk(const ChunkView& chunk, const DecodeOptions& options,
                           MemoryBudget& budget, WorkBudget& work, ChunkOrder& order,
                           SceneField* scene, SceneInfo& info) {
  const SceneHeader& h = info.header;
  const Expect expect = order.expect;
  if (chunk.type == kChunkHead && expect == Expect::kHead) {
    ECRF_RETURN_IF_ERROR(DecodeHeadChunk(chunk, options, budget, scene, info));
    if (h.scene_model == static_cast<uint8_t>(SceneModel::kForward)) {
      order.expect = Expect::kNdcFrame;
    } else {
      order.ExpectOccupancyOrTensor(h);
    }
  } else if (chunk.type == kChunkNdcFrame && expect == Expect::kNdcFrame) {
    ECRF_RETURN_IF_ERROR(ParseNdcFrame(chunk.data, chunk.size, &scene->ndc));
    info.ndc_bytes = chunk.size;
    order.ExpectOccupancyOrTensor(h);
  } else if (chunk.type == kChunkOccupancy && expect == Expect::kOccupancy) {
    ECRF_RETURN_IF_ERROR(
        DecodeOccupancyChunk(chunk, info.version_minor, &budget, &work, scene, &info));
    order.AdvanceTensor(h);
  } else if (chunk.type == kChunkCoefficients && expect == Expect::kCoefficients) {
    const int g = order.next_tensor / kTensorsPerSceneGrid;
    const int t = order.next_tensor % kTensorsPerSceneGrid;
    VmGrid* grid = g == 0 ? &scene->density : &scene->appearance;
    ECRF_RETURN_IF_ERROR(DecodeCoefficientChunk(chunk, h, g, t, info.version_minor, &budget, &work,
                                                grid, &info.tensors[g][t]));
    ++order.next_tensor;
    order.AdvanceTensor(h);
  } else if (chunk.type == kChunkMlpWeights && expect == Expect::kMlp) {
    ECRF_RETURN_IF_ERROR(
        DecodeMlpChunk(chunk, h, &budget, &work, info.version_minor, scene, &info));
    order.expect = Expect::kDone;
  } else {
    char name[5];
    ChunkTypeName(chunk.type, name);
    const bool known = chunk.type == kChunkHead || chunk.type == kChunkNdcFrame ||
                       chunk.type == kChunkOccupancy || chunk.type == kChunkCoefficients ||
                       chunk.type == kChunkMlpWeights;
    return Status::Error(known ? kErrCorrupt : kErrUnsupported,
                         known ? "chunk '%s' at offset %zu is out of order"
                               : "unknown critical chunk '%s' at offset %zu",
                         name, chunk.offset);
  }
  return Status::Ok();
}

// DecodeOptions::storage kInt16: the decoded grids converted to 16-bit values.
Status ConvertGridsToInt16(const SceneHeader& h, WorkBudget& work, SceneField* scene) {
  // The conversion reads and writes every grid value: one unit per 16.
  if (!work.Take(SceneGridValues(h) / 16)) return work.Refuse("16-bit grid storage");
  VmGrid converted;
  ECRF_RETURN_IF_ERROR(QuantizeGridInt16(scene->density, &converted));
  scene->density = static_cast<VmGrid&&>(converted);
  VmGrid converted_app;
  ECRF_RETURN_IF_ERROR(QuantizeGridInt16(scene->appearance, &converted_app));
  scene->appearance = static_cast<VmGrid&&>(converted_app);
  return Status::Ok();
}

// The stream's chunks in order: the critical ones decoded, the ancillary ones recorded, until
// DONE; then the grids in the storage asked for, and the scene validated.
Status DecodeChunks(const uint8_t* data, size_t size, const DecodeOptions& options,
                    MemoryBudget& budget, WorkBudget& work, SceneField* scene, SceneInfo& info) {
  ContainerReader reader;
  ECRF_RETURN_IF_ERROR(reader.Open(data, size));
  info.version_major = reader.version_major();
  info.version_minor = reader.version_minor();
  ChunkOrder order;
  for (;;) {
    ChunkView chunk;
    bool done = false;
    ECRF_RETURN_IF_ERROR(reader.Next(&chunk, &done));
    if (done) {
      ECRF_CHECK_OR_RETURN(order.expect == Expect::kDone, kErrCorrupt,
                           "DONE at offset %zu before the scene is complete (%s missing)",
                           chunk.offset, ExpectedChunkName(order.expect));
      break;
    }
    if (!IsCriticalChunk(chunk.type)) {
      RecordAncillaryChunk(chunk, info);
      continue;
    }
    ECRF_RETURN_IF_ERROR(DecodeCriticalChunk(chunk, options, budget, work, order, scene, info));
  }
  if (options.storage == GridStorage::kInt16) {
    ECRF_RETURN_IF_ERROR(ConvertGridsToInt16(info.header, work, scene));
  }
  // Every grid value is an IDCT output (|y| < 2^31) times step * 2^-Pf <= 2^60: finite by
  // construction, so the renderer need not scan (and page in) every value again.
  scene->grids_known_finite = true;
  return scene->Validate();
}

}  // namespace

Status DecodeScene(const uint8_t* data, size_t size, const DecodeOptions& options,
                   SceneField* scene, SceneInfo* info_out) {
  ECRF_CHECK_OR_RETURN(scene != nullptr, kErrInvalidArgument, "DecodeScene: null scene");
  ECRF_CHECK_OR_RETURN(
      options.storage == GridStorage::kFloat32 || options.storage == GridStorage::kInt16,
      kErrInvalidArgument, "DecodeScene: unknown grid storage");
  SceneInfo local_info;
  SceneInfo& info = info_out ? *info_out : local_info;
  info = SceneInfo();
  info.stream_bytes = size;
  MemoryBudget budget(options.max_memory_bytes);
  WorkBudget work(options.work_base, options.work_per_byte, size);
  const Status s = DecodeChunks(data, size, options, budget, work, scene, info);
  // Also after a refusal: what the stream had cost when it was refused.
  info.decode_work = work.spent();
  info.decode_budget = work.total();
  info.memory_bytes = budget.spent();
  return s;
}

}  // namespace dec
}  // namespace ecrf
