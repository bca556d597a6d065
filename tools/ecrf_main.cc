// The ecrf command-line tool: one binary, one subcommand per job.
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "ecrf/decoder.h"
#include "tools/benches.h"
#include "tools/commands.h"

namespace {

struct Command {
  const char* name;
  int (*run)(int argc, char** argv);
  const char* help;
};

int RunVersion(int, char**) {
  std::printf("ecrf %s (bitstream version %d)\n", ecrf_version_string(), ecrf_bitstream_version());
  return 0;
}

int RunBench(int argc, char** argv);

const Command kCommands[] = {
    {"version", RunVersion, "print the library and bitstream versions"},
    {"selfcheck", ecrf::tools::RunSelfCheck,
     "round-trip the entropy coder and check the integer IDCT against float64"},
    {"train", ecrf::tools::RunTrain, "train a TensoRF VM model: train --data DIR|--scene builtin|capture|forward -o RUN"},
    {"encode", ecrf::tools::RunEncode, "encode a trained run: encode RUN_DIR -o SCENE.ecrf"},
    {"info", ecrf::tools::RunInfo, "describe a stream: info SCENE.ecrf [--md5]"},
    {"render", ecrf::tools::RunRender,
     "render a stream: render SCENE.ecrf --views transforms_test.json|--orbit N -o OUT_DIR"},
    {"eval", ecrf::tools::RunEval, "PSNR/SSIM of a stream: eval SCENE.ecrf --data DIR"},
    {"conformance", ecrf::tools::RunConformance,
     "rebuild (--write DIR) or check (--check DIR) the conformance vectors"},
    {"report", ecrf::tools::RunReport,
     "rate-distortion and speed-error reports: report sweep|render|compare|plot"},
    {"bench", RunBench, "benchmarks: bench coder|idct|mlp|train [--json FILE]"},
};

struct Bench {
  const char* name;
  int (*run)(int argc, char** argv);
  const char* help;
  const char* usage;
};

const Bench kBenches[] = {
    {"coder", ecrf::tools::RunCoderBench, "entropy coder and coefficient coding", "[--json FILE]"},
    {"idct", ecrf::tools::RunIdctBench, "integer inverse DCT", "[--json FILE]"},
    {"mlp", ecrf::tools::RunMlpBench, "appearance MLP forward/backward GEMMs",
     "[--n N] [--threads 1,2] [--reps R] [--chunk ROWS] [--adam FLOATS] [--best] [--json FILE]"},
    {"train", ecrf::tools::RunTrainStepBench, "one training step at the 128^3 and 300^3 phases",
     "[--res N] [--rays N] [--reps N] [--threads 1,2] [--mask 0|1] [--early-stop T] [--blob-peak F] "
     "[--json FILE]"},
};

bool IsHelpFlag(const char* a) { return !std::strcmp(a, "--help") || !std::strcmp(a, "-h"); }

void PrintUsage(FILE* out) {
  std::fprintf(out, "usage: ecrf <command> [options]\n\ncommands:\n");
  for (const Command& c : kCommands) std::fprintf(out, "  %-10s %s\n", c.name, c.help);
}

int RunBench(int argc, char** argv) {
  if (argc < 2 || IsHelpFlag(argv[1])) {
    FILE* out = argc < 2 ? stderr : stdout;
    std::fprintf(out, "usage: ecrf bench <what> [options]\n");
    for (const Bench& b : kBenches) std::fprintf(out, "  %-8s %s\n", b.name, b.help);
    return argc < 2 ? 2 : 0;
  }
  for (const Bench& b : kBenches) {
    if (std::strcmp(argv[1], b.name) != 0) continue;
    for (int i = 2; i < argc; ++i) {
      if (IsHelpFlag(argv[i])) {
        std::printf("usage: ecrf bench %s %s\n  %s\n", b.name, b.usage, b.help);
        return 0;
      }
    }
    return b.run(argc - 1, argv + 1);
  }
  std::fprintf(stderr, "ecrf bench: unknown benchmark '%s'\n", argv[1]);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
    PrintUsage(argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  if (std::strcmp(argv[1], "--version") == 0) return RunVersion(0, nullptr);
  for (const Command& c : kCommands) {
    if (std::strcmp(argv[1], c.name) != 0) continue;
    try {
      return c.run(argc - 1, argv + 1);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "ecrf %s: error: %s\n", c.name, e.what());
      return 1;
    }
  }
  std::fprintf(stderr, "ecrf: unknown command '%s'\n\n", argv[1]);
  PrintUsage(stderr);
  return 2;
}
