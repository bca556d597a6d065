// The training flags, declared once (CLI11) for `ecrf train` and `ecrf report sweep`.
//
// A command line resolves in three layers, each overriding the one before wherever the flags
// stand on the line:
//   1. the preset (--preset; `tiny` for procedural scenes, else by the data: PresetForData),
//   2. the rate point, a base of settings (--rate low|medium|high|none; without --rate the
//      `medium` point, or `none` = plain TensoRF for --lambda-e 0; --target-size picks settings
//      by the target's share of the grid instead, trainer::ApplyTargetSizeDefaults),
//   3. every other flag, which changes only its own setting (--lambda-e 1e-10 keeps the point's
//      steps, MLP levels and grid schedule).
// The flags are declared after layers 1 and 2 are known, so --help shows the values a run of
// that command line would use.
#ifndef ECRF_TOOLS_TRAIN_FLAGS_H_
#define ECRF_TOOLS_TRAIN_FLAGS_H_

#include <map>
#include <string>
#include <vector>

#include "tools/cli.h"
#include "trainer/train/train_fields.h"

namespace ecrf {
namespace tools {

// Layers 1 and 2 of a command line (arguments without the command's name). Without --preset:
// `tiny` for --scene, else the preset of --data's size and kind (trainer::PresetForData), whose
// reason goes to *preset_reason when given.
trainer::TrainOptions BaseTrainOptions(const std::vector<std::string>& args,
                                       std::string* preset_reason = nullptr);

// The flags' text until FinishTrainFlags converts it into options.
struct TrainFlags {
  trainer::TrainOptions options;             // the base, then what the flags set
  std::map<std::string, std::string> texts;  // by field name (train_fields.def)
  std::string ranks;                         // --ranks D,A
  int threads = 0;
};

// The table line of the field named `key`; throws std::logic_error for names it lacks.
trainer::FieldInfo TrainFieldInfo(const std::string& key);

// Declares the training flags on app, bound to flags (whose options must hold the base).
void AddTrainFlags(CLI::App* app, TrainFlags* flags);

// After parsing: converts and checks the values, applies --target-size's defaults for the
// settings the line did not give and --threads. Throws std::invalid_argument naming the flag.
trainer::TrainOptions FinishTrainFlags(const CLI::App& app, TrainFlags* flags);

// ParseCommandLine, then FinishTrainFlags into *options: -1 when the command should run, else
// its exit code (0 after --help, 2 after a usage error, printed as one line).
int ParseTrainCommandLine(CLI::App* app, TrainFlags* flags, int argc, char** argv,
                          trainer::TrainOptions* options);

// The whole resolution of a training command line, with -o RUN_DIR: what `ecrf train ARGS`
// would run. Throws std::invalid_argument on any error (unknown flags included).
trainer::TrainOptions ResolveTrainOptions(const std::vector<std::string>& args);

// A short description of the resolved settings for the start of a run: the rate point and the
// settings that define a rate point (lambda_e, steps, levels, grid, schedule).
std::string DescribeSettings(const trainer::TrainOptions& options);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_TRAIN_FLAGS_H_
