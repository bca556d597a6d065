// `ecrf encode RUN_DIR -o scene.ecrf`: a trained checkpoint -> an .ecrf stream.
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "tools/cli_args.h"
#include "tools/commands.h"
#include "tools/encode_report.h"
#include "trainer/checkpoint.h"
#include "trainer/encode_rate_control.h"
#include "trainer/scene_encoder.h"
#include "trainer/trainer.h"

namespace ecrf {
namespace tools {
namespace {

const char kEncodeUsage[] =
    "usage: ecrf encode RUN_DIR|CHECKPOINT -o SCENE.ecrf [options]\n"
    "  --coef-bits 8|16     coefficient depth (default 8)\n"
    "  --mlp-f32            store the basis and MLP as float32 (default float16)\n"
    "  --target-size SIZE   the largest file of at most SIZE (e.g. 500KB, 1.2MB) by scaling every\n"
    "                       quantization step by one factor (searched)\n"
    "  --mlp-levels L       store them as integer levels, at most L per row, range-coded (MLPW\n"
    "                       precision 2, bitstream 1.1; e.g. 31)\n"
    "  --rounding-offset X  coefficient quantizer: floor(|c| / step + X), 0 < X <= 0.5 (default: the\n"
    "                       one the run trained through, else 0.5; smaller widens the dead zone)\n"
    "  --max-version 1.N    write a stream decoders of 1.N read (default 1.4; 1.0-1.3 use the\n"
    "                       older coefficient contexts, 2-3.5% more coefficient bytes)\n"
    "  --no-drop            keep rank components that decode to zero\n"
    "  --no-occupancy       leave the alpha mask out\n"
    "  --dct-block CxHxW    plane blocks when the checkpoint has no trained rate (default 16x16x16)\n"
    "  --line-block CxL     line blocks likewise (default 8x8)\n";

}  // namespace

int RunEncode(int argc, char** argv) {
  std::string input, output;
  trainer::EncodeOptions o;
  bool blocks_given = false, offset_given = false;
  size_t target_bytes = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&] { return FlagValue(argc, argv, &i); };
    if (a == "--help" || a == "-h") {
      std::fputs(kEncodeUsage, stdout);
      return 0;
    } else if (a == "-o" || a == "--out") {
      output = value();
    } else if (a == "--coef-bits") {
      o.coef_bits = ParseInt("--coef-bits", value());
    } else if (a == "--target-size") {
      target_bytes = trainer::ParseByteSize(value());
    } else if (a == "--mlp-levels") {
      o.mlp_max_level = std::max(1, ParseInt("--mlp-levels", value()));
    } else if (a == "--mlp-f32") {
      o.mlp_float32 = true;
    } else if (a == "--rounding-offset") {
      o.rounding_offset = ParseFloat("--rounding-offset", value());
      offset_given = true;
    } else if (a == "--max-version") {
      const std::string v = value();
      const size_t dot = v.find('.');
      const std::string minor = dot == std::string::npos ? "" : v.substr(dot + 1);
      if (v.substr(0, dot) != "1" || minor.size() != 1 || minor[0] < '0' || minor[0] > '0' + kVersionMinor) {
        std::fprintf(stderr, "ecrf encode: --max-version '%s' is not 1.0 .. 1.%d\n", v.c_str(), kVersionMinor);
        return 2;
      }
      o.max_version_minor = minor[0] - '0';
    } else if (a == "--no-drop") {
      o.drop_zero_components = false;
    } else if (a == "--no-occupancy") {
      o.include_occupancy = false;
    } else if (a == "--dct-block") {
      ParseShape("--dct-block", value(), 3, o.blocks.plane_block);
      blocks_given = true;
    } else if (a == "--line-block") {
      int shape[2];
      ParseShape("--line-block", value(), 2, shape);
      o.blocks.line_block[1] = shape[0];
      o.blocks.line_block[2] = shape[1];
      blocks_given = true;
    } else if (!a.empty() && a[0] == '-') {
      std::fprintf(stderr, "ecrf encode: unknown option '%s'\n\n%s", a.c_str(), kEncodeUsage);
      return 2;
    } else if (input.empty()) {
      input = a;
    } else {
      std::fprintf(stderr, "ecrf encode: more than one input\n\n%s", kEncodeUsage);
      return 2;
    }
  }
  if (input.empty() || output.empty()) {
    std::fprintf(stderr, "ecrf encode: needs an input and -o\n\n%s", kEncodeUsage);
    return 2;
  }
  const std::string ckpt = IsDirectory(input) ? input + "/checkpoint.ckpt" : input;
  trainer::RateState rate;
  const trainer::TensorfModel model = trainer::LoadModelFromCheckpoint(ckpt, &rate);
  if (rate.active) {
    // The steps and blocks the rate objective trained for: the trained rate is the file's rate.
    if (blocks_given) std::fprintf(stderr, "note: using the trained block shapes of %s\n", ckpt.c_str());
    o.blocks = rate.config;
    if (o.coef_bits == 8) o.steps = rate.steps;
    if (!offset_given) o.rounding_offset = rate.rounding_offset;
  } else if (!blocks_given) {
    o.blocks = rate.config;  // the run's block shapes (defaults for old checkpoints)
  }
  nlohmann::json meta;
  meta["encoder"] = "ecrf";
  meta["source"] = ckpt;
  o.metadata_json = meta.dump();
  trainer::EncodeReport report;
  std::vector<uint8_t> bytes;
  if (target_bytes > 0) {
    trainer::TargetSizeResult t = trainer::EncodeToTargetSize(model, o, target_bytes);
    bytes = std::move(t.bytes);
    report = t.report;
    std::printf("target %zu bytes: steps x%.4g after %d encodes, %zu bytes (%+.2f%%)\n", target_bytes, t.step_scale,
                t.encodes, bytes.size(), 100.0 * (double(bytes.size()) / double(target_bytes) - 1.0));
  } else {
    bytes = trainer::EncodeScene(model, o, &report);
  }
  trainer::WriteFileAtomically(output, bytes.data(), bytes.size());
  PrintEncodeReport(stdout, report);
  std::printf("wrote %s (%zu bytes)\n", output.c_str(), bytes.size());
  return 0;
}

}  // namespace tools
}  // namespace ecrf
