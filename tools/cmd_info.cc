// `ecrf info SCENE.ecrf [--md5]`: what a stream holds (chunks, sizes, grid, ranks, steps) and,
// with --md5, the checksums of its decoded grids.
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "conformance/grid_md5.h"
#include "decoder/render_work.h"
#include "tools/cli.h"
#include "tools/commands.h"
#include "tools/decoded_scene.h"
#include "trainer/train/rate_state.h"

namespace ecrf {
namespace tools {

namespace {

// The meta chunk is untrusted text: bytes other than printable ASCII (terminal escape sequences)
// are shown as \xNN and a long one is cut, so `ecrf info` prints a bounded, harmless line
// whatever the stream holds.
constexpr size_t kMetadataShown = 400;

std::string PrintableMetadata(const uint8_t* text, size_t size, size_t limit) {
  std::string out;
  for (size_t i = 0; i < size && i < limit; ++i) {
    const uint8_t c = text[i];
    if (c >= 0x20 && c < 0x7f) {
      out += char(c);  // printable ASCII; anything else, UTF-8 included (C1 controls), escaped
    } else {
      char hex[8];
      std::snprintf(hex, sizeof(hex), "\\x%02x", c);
      out += hex;
    }
  }
  if (size > limit) out += " ... (" + std::to_string(size - limit) + " more bytes)";
  return out;
}

// --md5 reads every decoded value twice (each tensor's checksum, then the whole grids'), about
// 7 ns a value here: two units a value (the decode budget's unit is a few ns, SPEC.md 8.1) are
// charged to what is left of the stream's decode budget before any hashing, so that a few
// hundred bytes declaring huge untouched grids cannot make `info --md5` hash gigabytes.
void ChargeChecksums(const LoadedScene& s, const std::string& path, uint64_t work_per_byte) {
  const uint64_t values =
      (s.field->density.StorageBytes() + s.field->appearance.StorageBytes()) / sizeof(float);
  const uint64_t budget = s.info.decode_budget;  // the decoder's, ~0 when there is no limit
  if (2 * values > budget - s.info.decode_work) {
    throw std::runtime_error(
        path + ": --md5 of its " + std::to_string(values) + " decoded values costs " +
        std::to_string(2 * values) + " units, past what its decode left of its budget of " +
        std::to_string(budget) + " (2^24 + " + std::to_string(work_per_byte) + " per byte of its " +
        std::to_string(s.bytes.size()) + " bytes; --decode-budget N, 0 for no limit)");
  }
}

}  // namespace

int RunInfo(int argc, char** argv) {
  std::string path;
  bool md5 = false;
  auto app = MakeCommand(
      "info", "what a stream holds: chunks, sizes, grid, ranks, quantization steps, metadata");
  app->add_option("SCENE", path, "the .ecrf stream")->type_name("FILE")->required();
  app->add_flag(
      "--md5", md5,
      "also print the MD5 of each decoded grid (SPEC.md 6.5, as the conformance vectors)");
  uint64_t decode_budget = dec::kDefaultDecodeWorkPerByte;
  app->add_option("--decode-budget", decode_budget,
                  "refuse streams whose decoding (and --md5) costs more than 2^24 + N units per "
                  "byte of the file (0 = no limit)")
      ->type_name("N")
      ->capture_default_str();
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  const LoadedScene s = LoadSceneFile(path, dec::GridStorage::kFloat32,
                                      dec::kDefaultDecodeMemoryBudget, decode_budget);
  if (md5) ChargeChecksums(s, path, decode_budget);
  const dec::SceneInfo& in = s.info;
  const SceneHeader& h = in.header;
  std::printf(
      "%s: ecrf stream version %u.%u, %zu bytes, decoded in %.1f ms (decode work %.1f per byte; "
      "budget %llu + %llu per byte)\n",
      path.c_str(), in.version_major, in.version_minor, in.stream_bytes, s.decode_seconds * 1e3,
      static_cast<double>(in.decode_work) /
          static_cast<double>(std::max<size_t>(1, in.stream_bytes)),
      static_cast<unsigned long long>(dec::kDecodeWorkBase),
      static_cast<unsigned long long>(dec::kDefaultDecodeWorkPerByte));
  const bool unbounded = h.scene_model == static_cast<uint8_t>(SceneModel::kUnbounded);
  const bool forward = h.scene_model == static_cast<uint8_t>(SceneModel::kForward);
  std::printf("box      [%g %g %g] - [%g %g %g]%s\n", h.aabb_min[0], h.aabb_min[1], h.aabb_min[2],
              h.aabb_max[0], h.aabb_max[1], h.aabb_max[2],
              unbounded
                  ? " (unbounded scene: the region of interest; space beyond it is contracted)"
              : forward ? " (forward-facing scene: in the NDC of the reference camera)"
                        : "");
  if (forward) {
    const NdcFrame& f = s.field->ndc;
    const float* m = f.world_to_ref;
    std::printf(
        "ndc      near plane %g, scale %g %g, world to reference [%g %g %g %g; %g %g %g %g; %g %g "
        "%g %g] (%u bytes)\n",
        f.near_plane, f.scale[0], f.scale[1], m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8],
        m[9], m[10], m[11], in.ndc_bytes);
  }
  std::printf("grid     %u x %u x %u; density ranks %u %u %u; appearance ranks %u %u %u\n",
              h.res[0], h.res[1], h.res[2], h.ranks[0][0], h.ranks[0][1], h.ranks[0][2],
              h.ranks[1][0], h.ranks[1][1], h.ranks[1][2]);
  std::printf(
      "render   %u samples/ray, step %g, near %g, far %g, background %g %g %g; density %s(x %+g)\n",
      h.num_samples, h.step_size, h.near_far[0], h.near_far[1], h.background[0], h.background[1],
      h.background[2], DensityActivationName(static_cast<DensityActivation>(h.density_activation)),
      h.density_shift);
  // The head: where the MLP runs (SPEC.md 7.6), mlp per coloured sample, deferred per ray; sh
  // spherical harmonics in place of the MLP (hidden 0, 7.6.2).
  const std::string sh_degree =
      h.hidden == 0 ? " (degree " + std::to_string(ShDegreeForFeatureDim(h.feature_dim)) + ")" : "";
  // One hidden layer (MLPW layers 1, SPEC.md 6.6) is named; two are TensoRF's, the default.
  const char* layers = h.hidden != 0 && in.mlp_hidden_layers == 1 ? " x 1 layer" : "";
  std::printf("mlp      %s head%s, features %u, PE %u/%u, hidden %u%s, %s\n",
              AppearanceName(in.head, h.hidden), sh_degree.c_str(), h.feature_dim,
              h.feature_pe_freqs, h.viewdir_pe_freqs, h.hidden, layers,
              in.mlp_precision_bits == 16   ? "float16"
              : in.mlp_precision_bits == 32 ? "float32"
                                            : "quantized (levels x row steps)");
  // What a view costs, in the units of the render work budget (SPEC.md 8, decoder/render_work.h).
  const dec::SampleCosts cost = dec::SceneSampleCosts(*s.field);
  std::printf(
      "cost     per sample %llu (position) + %llu (density) + %llu (colour)%s%s, in "
      "multiply-adds of the render work budget\n",
      static_cast<unsigned long long>(cost.position), static_cast<unsigned long long>(cost.density),
      static_cast<unsigned long long>(cost.color),
      in.head == HeadKind::kDeferred ? "; per coloured ray " : "",
      in.head == HeadKind::kDeferred ? std::to_string(cost.ray_head).c_str() : "");
  std::printf("\n%-20s %10s %8s %10s %10s %12s %8s%s\n", "chunk", "bytes", "bits", "block", "step",
              "coded blocks", "contexts", md5 ? "  md5 of decoded float32 values" : "");
  std::printf("%-20s %10u\n", "HEAD", in.head_bytes);
  if (h.has_occupancy) {
    std::printf("%-20s %10u   %dx%dx%d mask, %zu occupied voxels, %s contexts\n", "OCCU",
                in.occupancy_bytes, in.occupancy_res[0], in.occupancy_res[1], in.occupancy_res[2],
                in.occupied_voxels, in.occupancy_contexts ? "wide" : "narrow");
  }
  for (int g = 0; g < 2; ++g) {
    for (int t = 0; t < 6; ++t) {
      const dec::TensorChunkInfo& ti = in.tensors[g][t];
      if (!ti.present) {
        std::printf("%-20s %10s\n", encoder::RateTensorName(g * 6 + t), "rank 0");
        continue;
      }
      char block[32], coded[32];
      std::snprintf(block, sizeof(block), "%dx%dx%d", ti.block[0], ti.block[1], ti.block[2]);
      std::snprintf(coded, sizeof(coded), "%u/%u", ti.coded_blocks, ti.blocks);
      std::printf("%-20s %10u %8d %10s %10.4g %12s %8s", encoder::RateTensorName(g * 6 + t),
                  ti.payload_bytes, ti.coef_bits, block, double(ti.step), coded,
                  ti.contexts == 2   ? "neighbour"
                  : ti.contexts == 1 ? "wide"
                                     : "narrow");
      if (md5) {
        std::printf(
            "  %s",
            conformance::TensorMd5(g == 0 ? s.field->density : s.field->appearance, t).c_str());
      }
      std::printf("\n");
    }
  }
  std::printf("%-20s %10u\n", "MLPW", in.mlp_bytes);
  if (in.metadata_bytes) {
    std::printf("%-20s %10u   %s\n", "meta", in.metadata_bytes,
                PrintableMetadata(in.metadata, in.metadata_size, kMetadataShown).c_str());
  }
  if (md5) std::printf("\ngrids md5 %s\n", conformance::SceneGridMd5(*s.field).c_str());
  return 0;
}

}  // namespace tools
}  // namespace ecrf
