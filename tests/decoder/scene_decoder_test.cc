// Scene decoding: the conformance streams decode to their checksums, the hand-made ones are
// rebuilt bit for bit, every malformed stream is an error (never a crash), and the C API works.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "conformance/grid_md5.h"
#include "conformance/scene_vectors.h"
#include "decoder/camera.h"
#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"
#include "ecrf/decoder.h"
#include "format/byte_io.h"
#include "format/container.h"
#include "format/crc32.h"
#include "format/scene_header.h"

namespace ecrf {
namespace dec {
namespace {

const std::string kDir = std::string(ECRF_SOURCE_DIR) + "/tests/conformance/";

std::vector<uint8_t> ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)),
                              std::istreambuf_iterator<char>());
}

std::map<std::string, std::string> SceneManifest() {
  std::map<std::string, std::string> m;
  std::ifstream in(kDir + "scenes.md5");
  std::string file, md5;
  while (in >> file >> md5) m[file] = md5;
  return m;
}

Status Decode(const std::vector<uint8_t>& bytes, SceneField* field, SceneInfo* info = nullptr) {
  return DecodeScene(bytes.data(), bytes.size(), DecodeOptions(), field, info);
}

TEST(SceneDecoder, ConformanceScenesDecodeToTheirMd5) {
  const auto manifest = SceneManifest();
  ASSERT_EQ(manifest.size(), conformance::SceneVectors().size() + 1)
      << "missing " << kDir << "scenes.md5";
  for (const auto& [file, md5] : manifest) {
    SceneField field;
    const Status s = Decode(ReadFile(kDir + file), &field);
    ASSERT_TRUE(s.ok()) << file << ": " << s.message();
    EXPECT_EQ(conformance::SceneGridMd5(field), md5) << file;
  }
}

TEST(SceneDecoder, HandMadeVectorsAreRebuiltBitExactly) {
  for (const auto& v : conformance::SceneVectors()) {
    EXPECT_EQ(conformance::BuildSceneVector(v), ReadFile(kDir + v.name + ".ecrf"))
        << v.name << ": the stream syntax changed (see tests/conformance/README.md)";
  }
}

TEST(SceneDecoder, ReportsWhatTheStreamHolds) {
  for (const auto& v : conformance::SceneVectors()) {
    SceneField field;
    SceneInfo info;
    const std::vector<uint8_t> bytes =
        conformance::BuildSceneVector(v);  // info.metadata points here
    ASSERT_TRUE(Decode(bytes, &field, &info).ok()) << v.name;
    for (int g = 0; g < 2; ++g) {
      for (int t = 0; t < 6; ++t) {
        const TensorChunkInfo& ti = info.tensors[g][t];
        EXPECT_EQ(ti.present, v.ranks[g][t % 3] > 0) << v.name << " " << g << " " << t;
        if (!ti.present) continue;
        EXPECT_EQ(ti.coef_bits, v.coef_bits);
        const int* block = t < 3 ? v.plane_block : v.line_block;
        for (int a = 0; a < 3; ++a) EXPECT_EQ(ti.block[a], block[a]);
        EXPECT_LE(ti.coded_blocks, ti.blocks);
      }
      for (int m = 0; m < 3; ++m)
        EXPECT_EQ((g ? field.appearance : field.density).ranks[m], v.ranks[g][m]);
    }
    EXPECT_EQ(field.has_mask, v.occupancy != conformance::OccupancyKind::kNone);
    EXPECT_EQ(info.mlp_precision, v.mlp_precision);
    EXPECT_EQ(info.mlp_precision_bits, v.mlp_precision == 2 ? 0 : v.mlp_precision ? 32 : 16);
    ASSERT_NE(info.metadata, nullptr);
    EXPECT_EQ(std::string(reinterpret_cast<const char*>(info.metadata), info.metadata_size),
              std::string("{\"vector\":\"") + v.name + "\"}");
  }
}

// Recomputes every chunk CRC so mutations reach the chunk parsers instead of the checksum.
void FixCrcs(std::vector<uint8_t>* bytes) {
  size_t pos = 8;
  while (pos + 12 <= bytes->size()) {
    uint32_t length;
    std::memcpy(&length, bytes->data() + pos + 4, 4);
    if (length > bytes->size() - pos - 12) return;
    const uint32_t crc = Crc32(bytes->data() + pos, 8 + size_t(length));
    std::memcpy(bytes->data() + pos + 8 + length, &crc, 4);
    pos += 12 + length;
  }
}

TEST(SceneDecoder, EveryPrefixIsAnError) {
  for (const char* name : {"scene_16bit", "scene_ranks_dropped"}) {
    const std::vector<uint8_t> full = ReadFile(kDir + name + std::string(".ecrf"));
    ASSERT_FALSE(full.empty());
    for (size_t cut = 0; cut < full.size(); ++cut) {
      SceneField field;
      const Status s = DecodeScene(full.data(), cut, DecodeOptions(), &field, nullptr);
      ASSERT_FALSE(s.ok()) << name << " prefix " << cut;
      ASSERT_EQ(s.code(), kErrTruncated) << name << " prefix " << cut << ": " << s.message();
    }
  }
}

TEST(SceneDecoder, CorruptedStreamsFailCleanlyOrDecodeValidScenes) {
  std::mt19937 rng(17);
  int decoded = 0, failed = 0;
  for (const auto& v : conformance::SceneVectors()) {
    const std::vector<uint8_t> clean = conformance::BuildSceneVector(v);
    for (int trial = 0; trial < 300; ++trial) {
      std::vector<uint8_t> bytes = clean;
      const int flips = 1 + int(rng() % 4);
      for (int f = 0; f < flips; ++f) {
        const size_t at = 8 + rng() % (bytes.size() - 8);
        bytes[at] = trial % 3 == 0 ? uint8_t(rng()) : uint8_t(bytes[at] ^ (1u << (rng() % 8)));
      }
      FixCrcs(&bytes);
      SceneField field;
      const Status s = Decode(bytes, &field);
      if (s.ok()) {
        EXPECT_TRUE(field.Validate().ok());
        ++decoded;
      } else {
        EXPECT_NE(s.message()[0], '\0');
        ++failed;
      }
    }
  }
  EXPECT_GT(failed, 100);  // the parsers do reject what they see
  std::printf("  %d corrupted streams rejected, %d still decoded to valid scenes\n", failed,
              decoded);
}

// Chunk-level syntax errors, each with its category.
using Chunks = std::vector<std::pair<uint32_t, std::vector<uint8_t>>>;

// A stream's chunks (type, payload) in order; DONE included.
Chunks SplitChunks(const std::vector<uint8_t>& stream) {
  Chunks chunks;
  for (size_t pos = 8; pos < stream.size();) {
    uint32_t type, length;
    std::memcpy(&type, stream.data() + pos, 4);
    std::memcpy(&length, stream.data() + pos + 4, 4);
    chunks.emplace_back(type, std::vector<uint8_t>(stream.begin() + long(pos) + 8,
                                                   stream.begin() + long(pos) + 8 + length));
    pos += 12 + length;
  }
  return chunks;
}

TEST(SceneDecoder, ChunkOrderAndUnknownChunks) {
  const std::vector<uint8_t> good = conformance::BuildSceneVector(conformance::SceneVectors()[0]);
  Chunks chunks = SplitChunks(good);
  auto build = [](const Chunks& list) {
    ContainerWriter w;
    for (const auto& [type, payload] : list) {
      if (type != kChunkDone) w.AddChunk(type, payload);
    }
    return w.Finish();
  };
  SceneField field;
  ASSERT_TRUE(Decode(build(chunks), &field).ok());

  auto swapped = chunks;
  std::swap(swapped[1], swapped[2]);  // two COEF chunks out of order
  EXPECT_EQ(Decode(build(swapped), &field).code(), kErrCorrupt);

  auto no_head = chunks;
  no_head.erase(no_head.begin());
  EXPECT_EQ(Decode(build(no_head), &field).code(), kErrCorrupt);

  auto unknown_critical = chunks;
  unknown_critical.insert(unknown_critical.begin() + 1, {FourCC("ZZZZ"), {1, 2, 3}});
  EXPECT_EQ(Decode(build(unknown_critical), &field).code(), kErrUnsupported);

  auto unknown_ancillary = chunks;
  unknown_ancillary.insert(unknown_ancillary.begin() + 2, {FourCC("zzzz"), {1, 2, 3}});
  EXPECT_TRUE(Decode(build(unknown_ancillary), &field).ok());

  auto missing_mlp = chunks;
  missing_mlp.erase(missing_mlp.end() - 3);  // MLPW (before meta and DONE)
  EXPECT_EQ(Decode(build(missing_mlp), &field).code(), kErrCorrupt);
}

// The COEF `contexts` byte (SPEC.md 6.4.2): 1 (wide) only from version 1.4 on, as 1.0-1.3 decoders
// refuse it; unknown sets are unsupported.
TEST(SceneDecoder, CoefficientContextSetIsCheckedAgainstTheVersion) {
  const conformance::SceneVector& wide_vector = conformance::SceneVectors()[7];
  ASSERT_TRUE(wide_vector.wide_contexts);
  const std::vector<uint8_t> good = conformance::BuildSceneVector(wide_vector);
  ASSERT_EQ(good[5], 4);
  Chunks chunks = SplitChunks(good);
  auto build = [&chunks](uint8_t minor, uint8_t plane_contexts) {
    ContainerWriter w(minor);
    for (auto [type, payload] : chunks) {
      if (type == kChunkDone) continue;
      if (type == kChunkCoefficients && payload[1] < 3) payload[3] = plane_contexts;
      w.AddChunk(type, payload);
    }
    return w.Finish();
  };
  SceneField field;
  SceneInfo info;
  ASSERT_TRUE(DecodeScene(good.data(), good.size(), DecodeOptions(), &field, &info).ok());
  EXPECT_EQ(info.tensors[0][0].contexts, 1);  // planes wide
  EXPECT_EQ(info.tensors[0][3].contexts, 0);  // lines narrow
  EXPECT_EQ(build(4, 1), good);
  EXPECT_EQ(Decode(build(3, 1), &field).code(), kErrCorrupt);
  // The neighbour set (2) is known from 1.5 on; 3 is no set at all.
  EXPECT_EQ(Decode(build(4, 2), &field).code(), kErrCorrupt);
  EXPECT_EQ(Decode(build(5, 3), &field).code(), kErrUnsupported);
  EXPECT_EQ(Decode(build(6, 3), &field).code(), kErrUnsupported);
}

// SPEC.md 6.3: the OCCU contexts field, 0 narrow, 1 wide (1.5); reserved (0) before 1.5.
TEST(SceneDecoder, OccupancyContextSetIsCheckedAgainstTheVersion) {
  const conformance::SceneVector* vector = nullptr;
  for (const conformance::SceneVector& v : conformance::SceneVectors()) {
    if (std::string(v.name) == "scene_neighbour_contexts") vector = &v;
  }
  ASSERT_NE(vector, nullptr);
  const std::vector<uint8_t> good = conformance::BuildSceneVector(*vector);
  ASSERT_EQ(good[5], 5);
  const Chunks chunks = SplitChunks(good);
  // Relabels the stream and sets the OCCU contexts field (offset 30, u16).
  auto build = [&chunks](uint8_t minor, uint16_t contexts) {
    ContainerWriter w(minor);
    for (auto [type, payload] : chunks) {
      if (type == kChunkDone) continue;
      if (type == kChunkOccupancy) {
        payload[30] = static_cast<uint8_t>(contexts);
        payload[31] = static_cast<uint8_t>(contexts >> 8);
      }
      w.AddChunk(type, payload);
    }
    return w.Finish();
  };
  SceneField field;
  SceneInfo info;
  ASSERT_TRUE(DecodeScene(good.data(), good.size(), DecodeOptions(), &field, &info).ok());
  EXPECT_EQ(info.occupancy_contexts, 1);
  EXPECT_EQ(build(5, 1), good);
  const Status old = Decode(build(4, 1), &field);
  EXPECT_EQ(old.code(), kErrCorrupt);
  EXPECT_NE(std::string(old.message()).find("OCCU"), std::string::npos) << old.message();
  EXPECT_EQ(Decode(build(5, 2), &field).code(), kErrUnsupported);
  EXPECT_EQ(Decode(build(5, 256), &field).code(), kErrUnsupported);
  // The same mask read with the narrow contexts is another mask, or a damaged stream.
  SceneField narrow;
  const Status misread = Decode(build(5, 0), &narrow);
  EXPECT_TRUE(!misread.ok() || narrow.mask.occupied_count() != field.mask.occupied_count());
}

// SPEC.md 2.1, the version rule: a stream that uses a feature of a later minor version than its
// version_minor is corrupt, whichever feature; a later minor version than the decoder knows is
// accepted when the stream uses only known features.
TEST(SceneDecoder, EveryFeatureNeedsItsMinorVersion) {
  const std::map<std::string, int> feature_minor = {
      {"scene_quantized_mlp", 1}, {"scene_unbounded", 2},          {"scene_forward", 3},
      {"scene_wide_contexts", 4}, {"scene_neighbour_contexts", 5}, {"scene_relu_density", 9}};
  int checked = 0;
  for (const conformance::SceneVector& v : conformance::SceneVectors()) {
    const auto it = feature_minor.find(v.name);
    if (it == feature_minor.end()) continue;
    const std::vector<uint8_t> good = conformance::BuildSceneVector(v);
    ASSERT_EQ(good[5], it->second) << v.name;  // the encoder writes the lowest minor version
    const Chunks chunks = SplitChunks(good);
    // The chunks under another version; from 1.9 HEAD has its density_activation byte, so a
    // 90-byte one gets a 0 (softplus) appended, and `extra` more bytes for a newer version.
    auto relabel = [&chunks](uint8_t minor, std::vector<uint8_t> extra = {}) {
      ContainerWriter w(minor);
      for (auto [type, payload] : chunks) {
        if (type == kChunkHead) {
          if (payload.size() < SceneHeaderBytes(minor)) payload.push_back(0);
          payload.insert(payload.end(), extra.begin(), extra.end());
        }
        if (type != kChunkDone) w.AddChunk(type, payload);
      }
      return w.Finish();
    };
    SceneField field;
    const Status below = Decode(relabel(static_cast<uint8_t>(it->second - 1)), &field);
    EXPECT_EQ(below.code(), kErrCorrupt) << v.name << ": " << below.message();
    EXPECT_NE(std::string(below.message()).find("version_minor"), std::string::npos)
        << below.message();
    EXPECT_TRUE(Decode(relabel(static_cast<uint8_t>(it->second)), &field).ok()) << v.name;
    EXPECT_TRUE(Decode(relabel(200), &field).ok()) << v.name;
    // A newer version's HEAD may be longer: its later fields, zero, are features it does not use;
    // a set one needs a newer decoder. This version's own HEAD has no such bytes.
    EXPECT_TRUE(Decode(relabel(200, {0, 0, 0}), &field).ok()) << v.name;
    EXPECT_EQ(Decode(relabel(200, {0, 1}), &field).code(), kErrUnsupported) << v.name;
    EXPECT_EQ(Decode(relabel(kVersionMinor, {0}), &field).code(), kErrCorrupt) << v.name;
    ++checked;
  }
  EXPECT_EQ(checked, 6);
}

// A stream of a few hundred bytes that claims what the format allows but a device cannot afford.
std::vector<uint8_t> HostileStream(const uint16_t res[3], int rank, const int occ_res[3]) {
  SceneHeader h;
  for (int a = 0; a < 3; ++a) {
    h.res[a] = res[a];
    h.ranks[0][a] = h.ranks[1][a] = static_cast<uint16_t>(rank);
  }
  h.has_occupancy = occ_res != nullptr;
  h.step_size = 0.01f;
  h.num_samples = 600;
  ByteWriter head;
  WriteSceneHeader(h, 0, &head);
  ContainerWriter w;
  w.AddChunk(kChunkHead, head.bytes());
  if (occ_res != nullptr) {
    ByteWriter occ;
    for (int a = 0; a < 3; ++a) occ.F32(-1.5f);
    for (int a = 0; a < 3; ++a) occ.F32(1.5f);
    for (int a = 0; a < 3; ++a) occ.U16(static_cast<uint16_t>(occ_res[a]));
    occ.U16(0);
    occ.Bytes(std::vector<uint8_t>(64, 0));  // an all-empty mask codes to a few bytes
    w.AddChunk(kChunkOccupancy, occ.bytes());
  }
  return w.Finish();
}

TEST(SceneDecoder, MemoryBudgetIsCheckedBeforeAllocating) {
  const std::vector<uint8_t> bytes = ReadFile(kDir + "scene_2d_blocks.ecrf");
  SceneInfo info;
  SceneField field;
  ASSERT_TRUE(Decode(bytes, &field, &info).ok());
  const uint64_t grid_bytes = SceneGridValues(info.header) * 4;
  DecodeOptions o;
  o.max_memory_bytes = grid_bytes - 1;  // not even the grids
  SceneField refused;
  Status s = DecodeScene(bytes.data(), bytes.size(), o, &refused, nullptr);
  EXPECT_EQ(s.code(), kErrLimit) << s.message();
  EXPECT_NE(std::string(s.message()).find("HEAD: the grids need"), std::string::npos)
      << s.message();
  EXPECT_TRUE(refused.density.plane_f32[0].empty());
  o.max_memory_bytes = grid_bytes;  // the grids, but not the occupancy mask after them
  SceneField no_mask;
  s = DecodeScene(bytes.data(), bytes.size(), o, &no_mask, nullptr);
  EXPECT_EQ(s.code(), kErrLimit) << s.message();
  EXPECT_NE(std::string(s.message()).find("OCCU: the occupancy mask need"), std::string::npos)
      << s.message();
  EXPECT_FALSE(no_mask.has_mask);
  o.max_memory_bytes = 1 << 20;
  SceneField ok;
  EXPECT_TRUE(DecodeScene(bytes.data(), bytes.size(), o, &ok, nullptr).ok());
  EXPECT_TRUE(ok.grids_known_finite);
}

TEST(SceneDecoder, HostileSizesAreRefusedByTheDefaultBudget) {
  // 4096 x 4096 x 2 at rank 4: 537 MB of grids (within the format's 2^28 values) from a
  // ~150-byte stream.
  const uint16_t big[3] = {4096, 4096, 2};
  const std::vector<uint8_t> grid_bomb = HostileStream(big, 4, nullptr);
  EXPECT_LT(grid_bomb.size(), 200u);
  SceneField field;
  Status s = DecodeScene(grid_bomb.data(), grid_bomb.size(), DecodeOptions(), &field, nullptr);
  EXPECT_EQ(s.code(), kErrLimit) << s.message();
  EXPECT_TRUE(field.density.plane_f32[0].empty());
  EXPECT_NE(std::string(s.message()).find("memory budget of 268435456 bytes"), std::string::npos)
      << s.message();

  // A 2^31-voxel mask (288 MiB with its acceleration levels) behind a tiny grid.
  const uint16_t small[3] = {8, 8, 8};
  const int occ[3] = {4096, 4096, 128};
  const std::vector<uint8_t> mask_bomb = HostileStream(small, 1, occ);
  EXPECT_LT(mask_bomb.size(), 400u);
  SceneField mask_field;
  s = DecodeScene(mask_bomb.data(), mask_bomb.size(), DecodeOptions(), &mask_field, nullptr);
  EXPECT_EQ(s.code(), kErrLimit) << s.message();
  EXPECT_NE(std::string(s.message()).find("OCCU"), std::string::npos) << s.message();
  EXPECT_FALSE(mask_field.has_mask);
}

TEST(SceneDecoder, Int16StorageMatchesFloat) {
  const std::vector<uint8_t> bytes = ReadFile(kDir + "scene_builtin.ecrf");
  SceneField f32, i16;
  ASSERT_TRUE(Decode(bytes, &f32).ok());
  DecodeOptions o;
  o.storage = GridStorage::kInt16;
  ASSERT_TRUE(DecodeScene(bytes.data(), bytes.size(), o, &i16, nullptr).ok());
  EXPECT_EQ(i16.density.storage, GridStorage::kInt16);
  // 15-bit fixed point with the tensor's peak as full scale.
  for (int m = 0; m < 3; ++m) {
    const size_t n = f32.appearance.plane_count(m);
    float peak = 0.f;
    for (size_t i = 0; i < n; ++i) peak = std::max(peak, std::fabs(f32.appearance.plane_f32[m][i]));
    for (size_t i = 0; i < n; ++i) {
      const float back = i16.appearance.plane_i16[m][i] * i16.appearance.plane_scale[m];
      ASSERT_NEAR(back, f32.appearance.plane_f32[m][i], peak / 32767.f * 0.51f + 1e-12f);
    }
  }
}

TEST(DecoderCApi, DecodeInfoTensorRenderAndErrors) {
  ecrf_scene* scene = ecrf_scene_create();
  ASSERT_NE(scene, nullptr);
  const uint8_t garbage[16] = {'E', 'C', 'R', 'F', 1,   0,   0,   0,
                               'H', 'E', 'A', 'D', 255, 255, 255, 255};
  EXPECT_EQ(ecrf_scene_decode(scene, garbage, sizeof(garbage), ECRF_STORAGE_FLOAT32),
            ECRF_ERR_LIMIT);
  EXPECT_NE(std::strlen(ecrf_scene_message(scene)), 0u);
  ecrf_scene_info info;
  EXPECT_EQ(ecrf_scene_get_info(scene, &info), ECRF_ERR_INVALID_ARGUMENT);

  const std::vector<uint8_t> bytes = ReadFile(kDir + "scene_empty_occupancy.ecrf");
  ASSERT_EQ(ecrf_scene_decode(scene, bytes.data(), bytes.size(), ECRF_STORAGE_FLOAT32), ECRF_OK)
      << ecrf_scene_message(scene);
  EXPECT_STREQ(ecrf_scene_message(scene), "");
  ASSERT_EQ(ecrf_scene_get_info(scene, &info), ECRF_OK);
  EXPECT_EQ(info.grid_res[0], 8);
  EXPECT_EQ(info.has_occupancy, 1);
  EXPECT_EQ(info.stream_bytes, bytes.size());
  const float* data = nullptr;
  int shape[3];
  size_t count = 0;
  ASSERT_EQ(ecrf_scene_tensor(scene, 1, 0, &data, shape, &count), ECRF_OK);
  EXPECT_EQ(count, size_t(shape[0]) * shape[1] * shape[2]);
  EXPECT_EQ(ecrf_scene_tensor(scene, 2, 0, &data, shape, &count), ECRF_ERR_INVALID_ARGUMENT);

  // An empty occupancy mask: every pixel is the background (1, 0.5, 0), however the rays run.
  ecrf_camera cam;
  const Camera orbit = OrbitCamera(24, 16, 0.4f, 0.3f, 3.f);
  std::memcpy(cam.c2w, orbit.c2w, sizeof(cam.c2w));
  cam.fx = orbit.fx;
  cam.fy = orbit.fy;
  cam.cx = orbit.cx;
  cam.cy = orbit.cy;
  cam.width = orbit.width;
  cam.height = orbit.height;
  ecrf_render_options ro;
  ecrf_render_options_default(&ro);
  ro.num_threads = 2;
  std::vector<float> rgb(24 * 16 * 3);
  std::vector<uint8_t> rgba(24 * 16 * 4);
  ASSERT_EQ(ecrf_scene_render(scene, &cam, &ro, rgba.data(), rgb.data()), ECRF_OK)
      << ecrf_scene_message(scene);
  for (size_t p = 0; p < 24 * 16; ++p) {
    ASSERT_EQ(rgb[3 * p + 0], 1.f);
    ASSERT_EQ(rgb[3 * p + 1], 0.5f);
    ASSERT_EQ(rgb[3 * p + 2], 0.f);
    ASSERT_EQ(rgba[4 * p + 3], 0);
  }
  // The speed knobs reach the renderer through the C API: defaults leave the scene's process,
  // values out of range are refused with a message.
  EXPECT_EQ(ro.step_scale, 1.f);
  EXPECT_LT(ro.weight_threshold, 0.f);
  ro.step_scale = 2.f;
  ro.weight_threshold = 0.5f;
  EXPECT_EQ(ecrf_scene_render(scene, &cam, &ro, rgba.data(), nullptr), ECRF_OK);
  ro.step_scale = 100.f;
  EXPECT_EQ(ecrf_scene_render(scene, &cam, &ro, rgba.data(), nullptr), ECRF_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(ecrf_scene_message(scene)).find("step_scale"), std::string::npos);
  ro.step_scale = 1.f;
  cam.width = 0;
  EXPECT_LT(ecrf_scene_render(scene, &cam, &ro, rgba.data(), nullptr), 0);
  ecrf_scene_destroy(scene);
}

// The version and the budget defaults decoder.h states are those the library reports and uses.
TEST(DecoderCApi, VersionAndDefaultsAreTheHeaders) {
  EXPECT_EQ(ecrf_version(),
            unsigned{ECRF_VERSION_MAJOR << 16 | ECRF_VERSION_MINOR << 8 | ECRF_VERSION_PATCH});
  EXPECT_EQ(std::string(ecrf_version_string()), std::to_string(ECRF_VERSION_MAJOR) + "." +
                                                    std::to_string(ECRF_VERSION_MINOR) + "." +
                                                    std::to_string(ECRF_VERSION_PATCH));
  ecrf_render_options o;
  ecrf_render_options_default(&o);
  EXPECT_EQ(o.sample_budget, ECRF_DEFAULT_SAMPLE_BUDGET);
  EXPECT_EQ(o.work_budget, uint64_t{ECRF_DEFAULT_WORK_BUDGET});
  EXPECT_EQ(DecodeOptions().max_memory_bytes, ECRF_DEFAULT_MEMORY_BUDGET);
  EXPECT_EQ(DecodeOptions().work_per_byte, uint64_t{ECRF_DEFAULT_DECODE_BUDGET});
}

// What a renderer of its own reads through the C API is what the reference renderer uses: the
// scene constants, the mask's bits and the MLP parameters, for every conformance scene.
TEST(SceneDecoder, CApiExposesTheFieldOccupancyAndMlpOfTheReferenceRenderer) {
  for (const char* name :
       {"scene_builtin.ecrf", "scene_quantized_mlp.ecrf", "scene_ranks_dropped.ecrf",
        "scene_unbounded.ecrf", "scene_forward.ecrf"}) {
    SCOPED_TRACE(name);
    const std::vector<uint8_t> bytes = ReadFile(kDir + name);
    SceneField field;
    SceneInfo info;
    ASSERT_TRUE(DecodeScene(bytes.data(), bytes.size(), DecodeOptions(), &field, &info).ok());
    ecrf_scene* scene = ecrf_scene_create();
    ecrf_scene_field f;
    EXPECT_EQ(ecrf_scene_get_field(scene, &f), ECRF_ERR_INVALID_ARGUMENT);  // nothing decoded
    EXPECT_EQ(ecrf_scene_version(scene), ECRF_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(ecrf_scene_mlp_layers(scene), ECRF_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(ecrf_scene_density_activation(scene), ECRF_ERR_INVALID_ARGUMENT);
    ASSERT_EQ(ecrf_scene_decode(scene, bytes.data(), bytes.size(), ECRF_STORAGE_FLOAT32), ECRF_OK);
    ASSERT_EQ(ecrf_scene_get_field(scene, &f), ECRF_OK);
    EXPECT_EQ(ecrf_scene_model(scene), static_cast<int>(field.scene_model));
    // The file header's version: the unbounded model needs 1.2, the forward-facing one 1.3.
    EXPECT_EQ(ecrf_scene_version(scene), (info.version_major << 8) | info.version_minor);
    if (std::string(name) == "scene_unbounded.ecrf") EXPECT_EQ(ecrf_scene_version(scene), 0x0102);
    if (std::string(name) == "scene_forward.ecrf") EXPECT_EQ(ecrf_scene_version(scene), 0x0103);
    // One hidden layer needs 1.8 (SPEC.md 6.6).
    EXPECT_EQ(ecrf_scene_mlp_layers(scene),
              std::string(name) == "scene_one_hidden_layer.ecrf" ? 1 : 2);
    if (std::string(name) == "scene_one_hidden_layer.ecrf")
      EXPECT_EQ(ecrf_scene_version(scene), 0x0108);
    // ReLU density needs 1.9 (SPEC.md 6.2); every other vector has softplus.
    const bool relu = std::string(name) == "scene_relu_density.ecrf";
    EXPECT_EQ(ecrf_scene_density_activation(scene),
              relu ? ECRF_DENSITY_RELU : ECRF_DENSITY_SOFTPLUS);
    if (relu) EXPECT_EQ(ecrf_scene_version(scene), 0x0109);
    EXPECT_EQ(ecrf_scene_model(scene) == ECRF_SCENE_UNBOUNDED,
              std::string(name) == "scene_unbounded.ecrf");
    EXPECT_EQ(ecrf_scene_model(scene) == ECRF_SCENE_FORWARD,
              std::string(name) == "scene_forward.ecrf");
    float frame[15];
    if (field.scene_model == SceneModel::kForward) {
      ASSERT_EQ(ecrf_scene_ndc_frame(scene, frame), ECRF_OK);
      for (int k = 0; k < 12; ++k) EXPECT_EQ(frame[k], field.ndc.world_to_ref[k]);
      EXPECT_EQ(frame[12], field.ndc.scale[0]);
      EXPECT_EQ(frame[13], field.ndc.scale[1]);
      EXPECT_EQ(frame[14], field.ndc.near_plane);
    } else {
      EXPECT_EQ(ecrf_scene_ndc_frame(scene, frame), ECRF_ERR_INVALID_ARGUMENT);
    }
    EXPECT_EQ(f.density_shift, field.density_shift);
    EXPECT_EQ(f.distance_scale, field.distance_scale);
    EXPECT_EQ(f.weight_threshold, field.weight_threshold);
    const MlpConfig& c = field.mlp.config();
    EXPECT_EQ(f.mlp_products, field.appearance.total_rank());
    EXPECT_EQ(f.mlp_inputs, f.mlp_features + 3 + 2 * f.mlp_features * f.mlp_feature_freqs +
                                6 * f.mlp_viewdir_freqs);
    EXPECT_EQ(f.mlp_params, size_t(f.mlp_features) * f.mlp_products +
                                size_t(c.hidden) * f.mlp_inputs + size_t(c.hidden) * c.hidden +
                                3u * c.hidden + 2u * c.hidden + 3u);

    std::vector<float> params(f.mlp_params), expected(f.mlp_params);
    EXPECT_EQ(ecrf_scene_mlp_params(scene, params.data(), params.size() - 1),
              ECRF_ERR_INVALID_ARGUMENT);
    ASSERT_EQ(ecrf_scene_mlp_params(scene, params.data(), params.size()), ECRF_OK);
    ASSERT_TRUE(field.mlp.GetParams(expected.data(), expected.size()).ok());
    EXPECT_EQ(std::memcmp(params.data(), expected.data(), params.size() * sizeof(float)), 0);

    const uint8_t* bits = nullptr;
    int res[3] = {0, 0, 0};
    size_t nbytes = 0;
    if (field.has_mask) {
      ASSERT_EQ(ecrf_scene_occupancy(scene, &bits, res, &nbytes), ECRF_OK);
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(res[a], field.mask.res()[a]);
        EXPECT_EQ(f.occupancy_min[a], field.mask.aabb_min()[a]);
        EXPECT_EQ(f.occupancy_max[a], field.mask.aabb_max()[a]);
      }
      ASSERT_GE(nbytes, (field.mask.voxel_count() + 7) / 8);
      EXPECT_EQ(std::memcmp(bits, field.mask.bits(), (field.mask.voxel_count() + 7) / 8), 0);
    } else {
      EXPECT_EQ(ecrf_scene_occupancy(scene, &bits, res, &nbytes), ECRF_ERR_INVALID_ARGUMENT);
    }
    ecrf_scene_destroy(scene);
  }
}

}  // namespace
}  // namespace dec
}  // namespace ecrf
