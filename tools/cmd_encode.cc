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

namespace {

// The arguments of `ecrf encode`: the run, the output, and the settings flags, which change the
// run's own settings (their defaults are the encoder's, for a run that stores none).
struct EncodeFlags {
  std::string input, output, target_size, dct_block, line_block, max_version;
  int coef_bits = encoder::EncodeOptions().coef_bits, mlp_levels = 0;
  float rounding_offset = encoder::EncodeOptions().rounding_offset;
  float rdoq_lambda = encoder::EncodeOptions().rdoq_lambda;
  bool mlp_f32 = false, no_drop = false, no_occupancy = false, refresh_mask = false;
};

void AddEncodeFlags(CLI::App* app, EncodeFlags* f) {
  app->add_option("run", f->input, "run directory (or its checkpoint.ckpt)")
      ->required()
      ->type_name("RUN_DIR");
  app->add_option("-o,--out", f->output, "the .ecrf file to write (atomically)")
      ->required()
      ->type_name("SCENE.ecrf");
  app->add_option("--target-size", f->target_size,
                  "the largest file of at most SIZE (units B, KB, MB, KiB, MiB) by scaling every "
                  "quantization step "
                  "by one factor (searched); default: the run's --target-size, if any")
      ->type_name("SIZE");
  app->add_option("--mlp-levels", f->mlp_levels,
                  "code the basis and MLP as integer levels, at most L per row (0 = binary16); "
                  "default: the run's")
      ->type_name("L")
      ->check(CLI::Range(0, 32767));
  app->add_flag("--mlp-f32", f->mlp_f32,
                "store the basis and MLP as float32 (with --mlp-levels 0)");
  app->add_option("--coef-bits", f->coef_bits,
                  "coefficient depth (16: the 16-bit peak steps, not the trained ones)")
      ->check(CLI::IsMember({8, 16}))
      ->capture_default_str();
  app->add_option("--rounding-offset", f->rounding_offset,
                  "coefficient quantizer floor(|c| / step + X), 0 < X <= 0.5; default: the one the "
                  "run trained "
                  "through")
      ->type_name("X");
  app->add_option("--rdoq", f->rdoq_lambda,
                  "rate-distortion optimised quantization with lambda L (squared steps per bit; 0 "
                  "= off); default: the one the run trained through")
      ->type_name("L")
      ->check(CLI::Range(0.f, encoder::kMaxRdoqLambda));
  app->add_option("--max-version", f->max_version,
                  "write a stream decoders of 1.N read (default 1." +
                      std::to_string(kVersionMinor) +
                      "; 1.4 leaves out the neighbour coefficient and wide occupancy contexts, "
                      "1.6-2.3% larger files; "
                      "1.0-1.3 also the wide ones, 2-3.5% more)")
      ->type_name("1.N");
  app->add_flag("--no-drop", f->no_drop, "keep rank components that decode to zero");
  app->add_flag("--no-occupancy", f->no_occupancy, "leave the alpha mask out");
  app->add_flag("--refresh-mask", f->refresh_mask,
                "the alpha mask from the checkpoint's density, on the points of its mask (what "
                "training does when it ends; for the checkpoints of runs trained before it did)");
  app->add_option("--dct-block", f->dct_block,
                  "plane blocks of a run without a trained rate (default 16x16x16)")
      ->type_name("CxHxW");
  app->add_option("--line-block", f->line_block, "line blocks of such a run (default 8x8)")
      ->type_name("CxL");
}

bool Given(const CLI::App& app, const char* flag) { return app.count(flag) > 0; }

// What to encode with: the encoder's settings and the file size to aim at (0: none).
struct EncodeJob {
  encoder::EncodeOptions options;
  size_t target_bytes = 0;
};

// The run's own settings; flags change them, and the user is told which.
EncodeJob JobFromRunConfig(const trainer::CheckpointRunInfo& info, const trainer::RateState& rate,
                           const CLI::App& app, const EncodeFlags& f, size_t target_flag) {
  trainer::TrainOptions config = info.config;
  if (Given(app, "--mlp-levels")) config.mlp_levels = f.mlp_levels;
  if (Given(app, "--rounding-offset")) config.rounding_offset = f.rounding_offset;
  if (Given(app, "--rdoq")) config.rdoq_lambda = f.rdoq_lambda;
  if (Given(app, "--coef-bits")) config.coef_bits = f.coef_bits;
  if (Given(app, "--target-size")) config.target_bytes = target_flag;
  for (const std::string& c : trainer::ChangedSettings(info.config, config)) {
    std::fprintf(stderr, "note: the flags change the run's setting %s\n", c.c_str());
  }
  EncodeJob job;
  job.options = TrainedRunEncodeOptions(config, rate, info.iteration, info.lambda_e);
  job.target_bytes = config.target_bytes;
  job.options.coef_bits = config.coef_bits;
  if (!rate.active) job.options.steps.clear();  // a run without the rate objective: the peak steps
  return job;
}

// A checkpoint of an ecrf older than stored configurations: the flags and defaults alone.
EncodeJob JobFromFlags(const std::string& ckpt, const trainer::RateState& rate, const CLI::App& app,
                       const EncodeFlags& f, size_t target_flag) {
  std::fprintf(stderr,
               "note: %s stores no configuration (an older ecrf wrote it): encoding with the "
               "flags' settings, which may differ from what that run's `ecrf train` wrote\n",
               ckpt.c_str());
  EncodeJob job;
  encoder::EncodeOptions& o = job.options;
  o.blocks = rate.config;
  if (rate.active) {
    o.steps = rate.steps;
    o.rounding_offset = rate.rounding_offset;
    o.rdoq_lambda = rate.rdoq_lambda;
  }
  o.mlp_max_level = f.mlp_levels;
  if (Given(app, "--rounding-offset")) o.rounding_offset = f.rounding_offset;
  if (Given(app, "--rdoq")) o.rdoq_lambda = f.rdoq_lambda;
  job.target_bytes = target_flag;
  nlohmann::json meta;
  meta["encoder"] = "ecrf";
  meta["source"] = ckpt;
  o.metadata_json = meta.dump();
  o.coef_bits = f.coef_bits;
  return job;
}

// "1.N" of --max-version: N, at most the version this encoder writes.
int MaxVersionMinor(const std::string& v) {
  const size_t dot = v.find('.');
  const std::string minor = dot == std::string::npos ? "" : v.substr(dot + 1);
  if (v.substr(0, dot) != "1" || minor.size() != 1 || minor[0] < '0' ||
      minor[0] > '0' + kVersionMinor) {
    throw std::invalid_argument("--max-version '" + v + "' is not 1.0 .. 1." +
                                std::to_string(kVersionMinor));
  }
  return minor[0] - '0';
}

// --dct-block and --line-block shape the blocks of a run without a trained rate; a run with one
// keeps the shapes it trained.
void ApplyBlockFlags(const CLI::App& app, const EncodeFlags& f, const trainer::RateState& rate,
                     const std::string& ckpt, encoder::EncodeOptions* o) {
  if (!Given(app, "--dct-block") && !Given(app, "--line-block")) return;
  if (rate.active) {
    std::fprintf(stderr, "note: using the trained block shapes of %s\n", ckpt.c_str());
    return;
  }
  if (Given(app, "--dct-block")) ParseShape("--dct-block", f.dct_block, 3, o->blocks.plane_block);
  if (Given(app, "--line-block")) {
    int shape[2];
    ParseShape("--line-block", f.line_block, 2, shape);
    o->blocks.line_block[1] = shape[0];
    o->blocks.line_block[2] = shape[1];
  }
}

// The flags that shape the stream whatever the settings came from.
void ApplyStreamFlags(const CLI::App& app, const EncodeFlags& f, const trainer::RateState& rate,
                      const std::string& ckpt, encoder::EncodeOptions* o) {
  if (!(o->rounding_offset > 0.f && o->rounding_offset <= 0.5f)) {
    throw std::invalid_argument("--rounding-offset must be in (0, 0.5]");
  }
  if (o->coef_bits != 8) o->steps.clear();  // the trained steps are 8-bit steps
  o->mlp_float32 = f.mlp_f32;
  o->drop_zero_components = !f.no_drop;
  o->include_occupancy = !f.no_occupancy;
  if (Given(app, "--max-version")) o->max_version_minor = MaxVersionMinor(f.max_version);
  ApplyBlockFlags(app, f, rate, ckpt, o);
}

}  // namespace

int RunEncode(int argc, char** argv) {
  auto app = MakeCommand(
      "encode",
      "Encodes a trained run (its checkpoint) into an .ecrf file, with the settings the run was "
      "trained with; the flags below change them.\n"
      "usage: ecrf encode RUN_DIR|CHECKPOINT -o SCENE.ecrf [options]");
  EncodeFlags f;
  AddEncodeFlags(app.get(), &f);
  const int parsed = ParseCommandLine(app.get(), argc, argv);
  if (parsed >= 0) return parsed;
  size_t target_flag = 0;
  try {
    if (Given(*app, "--target-size"))
      target_flag = ParseSizeWithUnit("--target-size", f.target_size);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "ecrf encode: error: %s\n", e.what());
    return 2;
  }

  const std::string ckpt = IsDirectory(f.input) ? f.input + "/checkpoint.ckpt" : f.input;
  const trainer::CheckpointRunInfo info = trainer::ReadCheckpointRunInfo(ckpt);
  trainer::RateState rate;
  trainer::TensorfModel model = trainer::LoadModelFromCheckpoint(ckpt, &rate);
  if (f.refresh_mask) {
    const size_t before = model.alpha_mask() ? model.alpha_mask()->count() : 0;
    if (!model.RefreshAlphaMask(info.has_config ? info.config.mask_downscale : 1)) {
      std::fprintf(stderr, "ecrf encode: error: --refresh-mask: %s has no alpha mask\n",
                   ckpt.c_str());
      return 2;
    }
    std::printf("alpha mask from the checkpoint's density: %zu points occupied (its own: %zu)\n",
                model.alpha_mask()->count(), before);
  }
  EncodeJob job = info.has_config ? JobFromRunConfig(info, rate, *app, f, target_flag)
                                  : JobFromFlags(ckpt, rate, *app, f, target_flag);
  ApplyStreamFlags(*app, f, rate, ckpt, &job.options);
  const EncodedRun e = EncodeRun(model, job.options, job.target_bytes);
  if (job.target_bytes > 0) {
    std::printf("target %zu bytes: steps x%.4g after %d encodes, %zu bytes (%+.2f%%)\n",
                job.target_bytes, e.step_scale, e.encodes, e.bytes.size(),
                100.0 * (double(e.bytes.size()) / double(job.target_bytes) - 1.0));
  }
  trainer::WriteFileAtomically(f.output, e.bytes.data(), e.bytes.size());
  PrintEncodeReport(stdout, e.report);
  std::printf("wrote %s (%zu bytes)\n", f.output.c_str(), e.bytes.size());
  return 0;
}

}  // namespace tools
}  // namespace ecrf
