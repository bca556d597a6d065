// Entry points of the `ecrf bench <what>` subcommands; each prints figures and can write JSON.
#ifndef ECRF_TOOLS_BENCH_BENCHES_H_
#define ECRF_TOOLS_BENCH_BENCHES_H_

namespace ecrf {
namespace tools {

// `ecrf bench <what>`: argv[0] is "bench", argv[1] the benchmark's name.
int RunBench(int argc, char** argv);

// argv[0] is the subcommand name ("coder", "train", ...). Returns a process exit code.
int RunCoderBench(int argc, char** argv);
int RunIdctBench(int argc, char** argv);
int RunMlpBench(int argc, char** argv);
int RunRenderBench(int argc, char** argv);
int RunBudgetBench(int argc, char** argv);
int RunTrainStepBench(int argc, char** argv);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_BENCH_BENCHES_H_
