// The resolved configuration of a run: every TrainOptions field as JSON (RUN_DIR/config.json and
// the checkpoint's "config"), read back by `ecrf encode RUN` and `--resume`, so that a later
// command rebuilds exactly what the run did instead of re-deriving it from defaults that may
// have changed.
//
// Fields are of two kinds: settings, which change what a run trains or writes (a different value
// gives a different file), and bookkeeping (where it writes, how it scores, checkpoints), which
// does not. `--resume` refuses a changed setting; bookkeeping may change freely.
#ifndef ECRF_TRAINER_TRAIN_TRAIN_CONFIG_H_
#define ECRF_TRAINER_TRAIN_TRAIN_CONFIG_H_

#include <string>
#include <vector>

#include "trainer/train/train_options.h"

namespace ecrf {
namespace trainer {

// Version of the config.json layout (a reader refuses newer ones).
constexpr int kTrainConfigVersion = 1;

// The options as a JSON object {"config_version", "settings": {...}, "bookkeeping": {...}},
// indented by `indent` spaces (-1: one line).
std::string TrainConfigToJson(const TrainOptions& options, int indent = 2);

// The options a config.json describes. Fields it lacks keep the defaults of its preset (configs
// written before a field existed). Throws std::runtime_error naming `where` on malformed JSON,
// a newer config_version or a field of the wrong type.
TrainOptions TrainConfigFromJson(const std::string& text, const std::string& where);

// The settings (not the bookkeeping) that differ, one "name: before -> after" line each.
std::vector<std::string> ChangedSettings(const TrainOptions& before, const TrainOptions& after);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_TRAIN_CONFIG_H_
