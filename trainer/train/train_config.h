// The resolved configuration of a run: every TrainOptions field as JSON (RUN_DIR/config.json and
// the checkpoint's "config"), read back by `ecrf encode RUN` and `--resume`, so that a later
// command rebuilds exactly what the run did instead of re-deriving it from defaults that may
// have changed.
//
// Recorded fields are of two kinds (FieldKind in train_fields.def): settings, which change what a
// run trains or writes (a different value gives a different file), and bookkeeping (where it
// writes, how it scores, checkpoints), which does not. `--resume` refuses a changed setting;
// bookkeeping may change freely. Fields about one command (--resume, --overwrite) are not recorded.
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
// a newer config_version, a field of the wrong type or a value its table line does not admit.
TrainOptions TrainConfigFromJson(const std::string& text, const std::string& where);

// Sets the fields a JSON object names ({"iters": 3000, ...}: a preset) in *o. Throws
// std::invalid_argument naming `where` for a name the table lacks, std::runtime_error for a value
// of the wrong type.
void ApplySettingsJson(const std::string& text, const std::string& where, TrainOptions* o);

// The settings (not the bookkeeping) that differ, one "name: before -> after" line each.
std::vector<std::string> ChangedSettings(const TrainOptions& before, const TrainOptions& after);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_TRAIN_CONFIG_H_
