// `ecrf encode RUN_DIR -o scene.ecrf`: a trained run -> an .ecrf stream.
//
// A run's checkpoint stores its resolved configuration (trainer/train/train_config.h): the encoder
// settings come from it, so `encode RUN` writes the bytes `ecrf train` wrote unless a flag changes
// a setting, and then it says which.
#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "encoder/coef_rdoq.h"
#include "tools/cli.h"
#include "tools/cli_args.h"
#include "tools/commands.h"
#include "tools/encode_report.h"
#include "tools/encode_run.h"
#include "trainer/data/file_io.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/train_config.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {

int RunEncode(int argc, char** argv) {
  auto app = MakeCommand(
      "encode",
      "Encodes a trained run (its checkpoint) into an .ecrf file, with the settings the run was "
      "trained with; the flags below change them.\n"
      "usage: ecrf encode RUN_DIR|CHECKPOINT -o SCENE.ecrf [options]");
  std::string input, output, target_size, dct_block, line_block, max_version;
  encoder::EncodeOptions defaults;
  int coef_bits = defaults.coef_bits, mlp_levels = 0;
  float rounding_offset = defaults.rounding_offset, rdoq_lambda = defaults.rdoq_lambda;
  bool mlp_f32 = false, no_drop = false, no_occupancy = false;
  app->add_option("run", input, "run directory (or its checkpoint.ckpt)")
      ->required()
      ->type_name("RUN_DIR");
  app->add_option("-o,--out", output, "the .ecrf file to write (atomically)")
      ->required()
      ->type_name("SCENE.ecrf");
  app->add_option("--target-size", target_size,
                  "the largest file of at most SIZE (units B, KB, MB, KiB, MiB) by scaling every "
                  "quantization step "
                  "by one factor (searched); default: the run's --target-size, if any")
      ->type_name("SIZE");
  app->add_option("--mlp-levels", mlp_levels,
                  "code the basis and MLP as integer levels, at most L per row (0 = binary16); "
                  "default: the run's")
      ->type_name("L")
      ->check(CLI::Range(0, 32767));
  app->add_flag("--mlp-f32", mlp_f32, "store the basis and MLP as float32 (with --mlp-levels 0)");
  app->add_option("--coef-bits", coef_bits,
                  "coefficient depth (16: the 16-bit peak steps, not the trained ones)")
      ->check(CLI::IsMember({8, 16}))
      ->capture_default_str();
  app->add_option("--rounding-offset", rounding_offset,
                  "coefficient quantizer floor(|c| / step + X), 0 < X <= 0.5; default: the one the "
                  "run trained "
                  "through")
      ->type_name("X");
  app->add_option("--rdoq", rdoq_lambda,
                  "rate-distortion optimised quantization with lambda L (squared steps per bit; 0 "
                  "= off); default: the one the run trained through")
      ->type_name("L")
      ->check(CLI::Range(0.f, encoder::kMaxRdoqLambda));
  app->add_option("--max-version", max_version,
                  "write a stream decoders of 1.N read (default 1." +
                      std::to_string(kVersionMinor) +
                      "; 1.4 leaves out the neighbour coefficient and wide occupancy contexts, "
                      "1.6-2.3% larger files; "
                      "1.0-1.3 also the wide ones, 2-3.5% more)")
      ->type_name("1.N");
  app->add_flag("--no-drop", no_drop, "keep rank components that decode to zero");
  app->add_flag("--no-occupancy", no_occupancy, "leave the alpha mask out");
  app->add_option("--dct-block", dct_block,
                  "plane blocks of a run without a trained rate (default 16x16x16)")
      ->type_name("CxHxW");
  app->add_option("--line-block", line_block, "line blocks of such a run (default 8x8)")
      ->type_name("CxL");
  const int parsed = ParseCommandLine(app.get(), argc, argv);
  if (parsed >= 0) return parsed;
  auto given = [&](const char* flag) { return app->count(flag) > 0; };
  size_t target_flag = 0;
  try {
    if (given("--target-size")) target_flag = ParseSizeWithUnit("--target-size", target_size);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "ecrf encode: error: %s\n", e.what());
    return 2;
  }

  const std::string ckpt = IsDirectory(input) ? input + "/checkpoint.ckpt" : input;
  const trainer::CheckpointRunInfo info = trainer::ReadCheckpointRunInfo(ckpt);
  trainer::RateState rate;
  const trainer::TensorfModel model = trainer::LoadModelFromCheckpoint(ckpt, &rate);

  encoder::EncodeOptions o;
  size_t target_bytes = 0;
  if (info.has_config) {
    // The run's own settings; flags change them, and the user is told which.
    trainer::TrainOptions config = info.config;
    if (given("--mlp-levels")) config.mlp_levels = mlp_levels;
    if (given("--rounding-offset")) config.rounding_offset = rounding_offset;
    if (given("--rdoq")) config.rdoq_lambda = rdoq_lambda;
    if (given("--coef-bits")) config.coef_bits = coef_bits;
    if (given("--target-size")) config.target_bytes = target_flag;
    for (const std::string& c : trainer::ChangedSettings(info.config, config)) {
      std::fprintf(stderr, "note: the flags change the run's setting %s\n", c.c_str());
    }
    o = TrainedRunEncodeOptions(config, rate, info.iteration, info.lambda_e);
    target_bytes = config.target_bytes;
    coef_bits = config.coef_bits;
    if (!rate.active) o.steps.clear();  // a run without the rate objective: the peak steps
  } else {
    // A checkpoint of an ecrf older than stored configurations: the flags and defaults alone.
    std::fprintf(
        stderr,
        "note: %s stores no configuration (an older ecrf wrote it): encoding with the flags' "
        "settings, which may differ from what that run's `ecrf train` wrote\n",
        ckpt.c_str());
    o.blocks = rate.config;
    if (rate.active) {
      o.steps = rate.steps;
      o.rounding_offset = rate.rounding_offset;
      o.rdoq_lambda = rate.rdoq_lambda;
    }
    o.mlp_max_level = mlp_levels;
    if (given("--rounding-offset")) o.rounding_offset = rounding_offset;
    if (given("--rdoq")) o.rdoq_lambda = rdoq_lambda;
    target_bytes = target_flag;
    nlohmann::json meta;
    meta["encoder"] = "ecrf";
    meta["source"] = ckpt;
    o.metadata_json = meta.dump();
  }
  if (!(o.rounding_offset > 0.f && o.rounding_offset <= 0.5f)) {
    throw std::invalid_argument("--rounding-offset must be in (0, 0.5]");
  }
  o.coef_bits = coef_bits;
  if (coef_bits != 8) o.steps.clear();  // the trained steps are 8-bit steps
  o.mlp_float32 = mlp_f32;
  o.drop_zero_components = !no_drop;
  o.include_occupancy = !no_occupancy;
  if (given("--max-version")) {
    const std::string& v = max_version;
    const size_t dot = v.find('.');
    const std::string minor = dot == std::string::npos ? "" : v.substr(dot + 1);
    if (v.substr(0, dot) != "1" || minor.size() != 1 || minor[0] < '0' ||
        minor[0] > '0' + kVersionMinor) {
      throw std::invalid_argument("--max-version '" + v + "' is not 1.0 .. 1." +
                                  std::to_string(kVersionMinor));
    }
    o.max_version_minor = minor[0] - '0';
  }
  if (given("--dct-block") || given("--line-block")) {
    if (rate.active) {
      std::fprintf(stderr, "note: using the trained block shapes of %s\n", ckpt.c_str());
    } else {
      if (given("--dct-block")) ParseShape("--dct-block", dct_block, 3, o.blocks.plane_block);
      if (given("--line-block")) {
        int shape[2];
        ParseShape("--line-block", line_block, 2, shape);
        o.blocks.line_block[1] = shape[0];
        o.blocks.line_block[2] = shape[1];
      }
    }
  }
  const EncodedRun e = EncodeRun(model, o, target_bytes);
  if (target_bytes > 0) {
    std::printf("target %zu bytes: steps x%.4g after %d encodes, %zu bytes (%+.2f%%)\n",
                target_bytes, e.step_scale, e.encodes, e.bytes.size(),
                100.0 * (double(e.bytes.size()) / double(target_bytes) - 1.0));
  }
  trainer::WriteFileAtomically(output, e.bytes.data(), e.bytes.size());
  PrintEncodeReport(stdout, e.report);
  std::printf("wrote %s (%zu bytes)\n", output.c_str(), e.bytes.size());
  return 0;
}

}  // namespace tools
}  // namespace ecrf
