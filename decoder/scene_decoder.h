// Decodes an .ecrf stream into a SceneField: container -> HEAD -> OCCU -> COEF (entropy decoding,
// integer inverse DCT, written straight into the final grid layout) -> MLPW (SPEC.md section 6).
//
// The grids are the normative output: the same bits on every platform. Every size is checked
// against SPEC.md section 8 before anything is allocated, and every chunk against the bytes it
// has, so any byte string gives either a scene or an error status, never a crash.
#ifndef ECRF_DECODER_SCENE_DECODER_H_
#define ECRF_DECODER_SCENE_DECODER_H_

#include <cstddef>
#include <cstdint>

#include "decoder/field.h"
#include "ecrf/decoder.h"
#include "format/scene_header.h"
#include "format/status.h"

namespace ecrf {
namespace dec {

inline constexpr uint64_t kDefaultDecodeMemoryBudget = ECRF_DEFAULT_MEMORY_BUDGET;
// Decode work (SPEC.md 8), in range-decoded symbols or what takes as long: a stream may cost
// kDecodeWorkBase plus DecodeOptions::work_per_byte per byte of its size.
inline constexpr uint64_t kDecodeWorkBase = uint64_t{1} << 24;
inline constexpr uint64_t kDefaultDecodeWorkPerByte = ECRF_DEFAULT_DECODE_BUDGET;

struct DecodeOptions {
  // kInt16 halves the grid memory (values rounded to 16-bit fixed point with one scale per
  // tensor after the normative float32 reconstruction).
  GridStorage storage = GridStorage::kFloat32;
  // Memory budget of the decoded scene: grids (float32, plus the 16-bit copy while converting),
  // occupancy mask with its acceleration levels, and MLP. Each chunk's need is checked against
  // what is left before anything is allocated (kErrLimit). Within the format's own limits a few
  // hundred bytes of stream can describe 1 GiB of all-zero grids and 2.5 KB of OCCU a 256 MiB
  // mask, so the default (ECRF_DEFAULT_MEMORY_BUDGET, 10x a 400x400 Synthetic-NeRF scene) keeps
  // hostile files cheap; applications that decode larger scenes raise it, small devices lower it.
  uint64_t max_memory_bytes = kDefaultDecodeMemoryBudget;
  // Decode work budget: kDecodeWorkBase + work_per_byte x the stream's size, in symbols (a coded
  // block's inverse DCT counts what it costs in symbols' time); 0: no limit. Within the format's
  // limits 30 KB of OCCU can flag 2^31 voxels for decoding and 8 KB of COEF can code 65,536
  // blocks to their last position; trained streams cost 14-110 per byte (docs/
  // benchmarks-and-fuzzing.md), so the default (ECRF_DEFAULT_DECODE_BUDGET) leaves them unchanged
  // and keeps any stream of 64 KB under a second. Checked as the work comes, before it is spent
  // (kErrLimit).
  uint64_t work_per_byte = kDefaultDecodeWorkPerByte;
  // The units every stream may spend whatever its size (with work_per_byte > 0).
  uint64_t work_base = kDecodeWorkBase;
};

// What the stream held, for `ecrf info` and reports.
struct TensorChunkInfo {
  bool present = false;
  int coef_bits = 0;
  int contexts = 0;  // coefficient context set: 0 narrow, 1 wide (1.4)
  int block[3] = {0, 0, 0};
  float step = 0.f;
  uint32_t payload_bytes = 0;
  uint32_t blocks = 0;
  uint32_t coded_blocks = 0;  // blocks with a nonzero coefficient
};

struct SceneInfo {
  SceneHeader header;
  uint8_t version_major = 0, version_minor = 0;
  size_t stream_bytes = 0;
  uint32_t head_bytes = 0, ndc_bytes = 0, occupancy_bytes = 0, mlp_bytes = 0, metadata_bytes = 0;
  uint32_t other_ancillary_bytes = 0;
  int mlp_precision = 0;                 // MLPW precision field: 0 float16, 1 float32, 2 quantized
  int mlp_precision_bits = 0;            // 16 or 32 for floating weights, 0 for quantized
  HeadKind head = HeadKind::kPerSample;  // MLPW head field (1.6)
  int mlp_hidden_layers = 2;             // MLPW layers field: 1 or 2 (1.8)
  int occupancy_res[3] = {0, 0, 0};
  size_t occupied_voxels = 0;
  uint8_t occupancy_contexts = 0;  // the OCCU contexts field: 0 narrow, 1 wide (1.5)
  TensorChunkInfo tensors[kNumSceneGrids][kTensorsPerSceneGrid];
  // The meta chunk (UTF-8 JSON), pointing into the caller's buffer; null if absent.
  const uint8_t* metadata = nullptr;
  uint32_t metadata_size = 0;
  uint64_t decode_work = 0;    // what the stream cost against the decode work budget
  uint64_t decode_budget = 0;  // that budget (~0: no limit), for work charged after decoding
  uint64_t memory_bytes = 0;   // what it took of the memory budget (grids, mask, MLP)
};

// Decodes `data` into *scene (replacing its contents). info may be null.
Status DecodeScene(const uint8_t* data, size_t size, const DecodeOptions& options,
                   SceneField* scene, SceneInfo* info);

}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_DECODER_SCENE_DECODER_H_
