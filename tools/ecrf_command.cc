// The `ecrf` command line: which subcommand runs, `ecrf help [CMD]`, the version, and the one
// place where an exception from a command becomes "ecrf CMD: error: ..." and exit code 1.
#include <cstdio>
#include <exception>
#include <string>

#include "ecrf/decoder.h"
#include "format/container.h"
#include "tools/bench/benches.h"
#include "tools/cli.h"
#include "tools/commands.h"
#include "tools/report/report.h"
#include "tools/subcommands.h"

namespace ecrf {
namespace tools {
namespace {

// One version story (#61): the library's version, and the bitstream versions it reads and writes
// (a file says its own, `ecrf info`); SPEC.md names both in its header and section 9.
void PrintVersion() {
  std::printf(
      "ecrf %s: reads bitstream %d.0 to %d.%d, writes each stream at the lowest of them its "
      "features need (SPEC.md)\n",
      ecrf_version_string(), ecrf_bitstream_version(), ecrf_bitstream_version(),
      ecrf_bitstream_version_minor());
}

int RunVersion(int argc, char** argv) {
  auto app = MakeCommand("version",
                         "print the library and bitstream versions (also ecrf --version, ecrf -V)");
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  PrintVersion();
  return 0;
}

const SubcommandTable& BenchTable() {
  static const SubcommandTable table = {
      "ecrf bench",
      "benchmark",
      {
          {"budgets", RunBudgetBench,
           "the costliest small streams against the decode and render budgets"},
          {"coder", RunCoderBench, "entropy coder and coefficient coding"},
          {"idct", RunIdctBench, "integer inverse DCT"},
          {"mlp", RunMlpBench,
           "appearance MLP forward/backward GEMMs and Adam against the CPU's FMA peak"},
          {"render", RunRenderBench,
           "the renderer on a synthetic scene: ms per view and samples per second"},
          {"train", RunTrainStepBench, "one training step at the 128^3 and 300^3 phases"},
      },
      "`ecrf bench <benchmark> --help` (or `ecrf help bench <benchmark>`) for the options of "
      "each;\n"
      "each can write its figures as JSON (--json FILE).\n"};
  return table;
}

const SubcommandTable& EcrfTable() {
  static const SubcommandTable table = {
      "ecrf",
      "command",
      {
          {"version", RunVersion, "print the library and bitstream versions"},
          {"selfcheck", RunSelfCheck,
           "round-trip the entropy coder and check the integer IDCT against float64"},
          {"prepare", RunPrepare,
           "posed images from photos or a video (COLMAP): prepare PHOTOS|VIDEO -o DATA"},
          {"train", RunTrain, "train a TensoRF VM model: train --data DIR|--scene NAME -o RUN"},
          {"encode", RunEncode, "encode a trained run: encode RUN_DIR -o SCENE.ecrf"},
          {"info", RunInfo, "describe a stream: info SCENE.ecrf [--md5]"},
          {"render", RunRender,
           "render a stream: render SCENE.ecrf --views transforms_test.json|--orbit N -o OUT_DIR"},
          {"eval", RunEval, "PSNR/SSIM of a stream: eval SCENE.ecrf --data DIR"},
          {"conformance", RunConformance,
           "rebuild (--write DIR) or check (--check DIR) the conformance vectors"},
          {"report", RunReport,
           "rate-distortion and speed-error reports: report sweep|render|compare|plot"},
          {"bench", RunBench, "benchmarks: bench coder|idct|mlp|render|train [--json FILE]"},
      },
      "`ecrf help <command>` (or `ecrf <command> --help`) for the options of each; ecrf "
      "--version.\n"};
  return table;
}

}  // namespace

int RunBench(int argc, char** argv) { return RunSubcommand(BenchTable(), argc, argv); }

int RunEcrf(int argc, char** argv) {
  if (argc == 2 && (std::string(argv[1]) == "--version" || std::string(argv[1]) == "-V")) {
    PrintVersion();
    return 0;
  }
  // The command an error belongs to: `ecrf help CMD` runs CMD too.
  const int named = argc > 2 && std::string(argv[1]) == "help" ? 2 : 1;
  const std::string command =
      argc > named && FindSubcommand(EcrfTable(), argv[named]) ? argv[named] : "";
  try {
    return RunSubcommand(EcrfTable(), argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ecrf%s%s: error: %s\n", command.empty() ? "" : " ", command.c_str(),
                 e.what());
    return 1;
  }
}

}  // namespace tools
}  // namespace ecrf
