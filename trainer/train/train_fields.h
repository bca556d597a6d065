// The table of training settings (train_fields.def) as a visitor: every path that reads or
// writes TrainOptions field by field (config.json, the checkpoint, the flags, validation, tests)
// walks this one list, so a field added to the table reaches all of them.
#ifndef ECRF_TRAINER_TRAIN_TRAIN_FIELDS_H_
#define ECRF_TRAINER_TRAIN_TRAIN_FIELDS_H_

#include "trainer/train/train_options.h"

namespace ecrf::trainer {

// Calls f(info, field) for every field of o in table order; info.key is the field's name.
// Options is TrainOptions or const TrainOptions.
template <class Options, class F>
void ForEachTrainField(Options& o, F&& f) {
#define ECRF_TRAIN_FIELD(type, name, info, ...) f(FieldInfo(info).Named(#name), o.name);
#include "trainer/train/train_fields.def"
#undef ECRF_TRAIN_FIELD
}

// The number of fields in the table.
inline int TrainFieldCount() {
  int count = 0;
  const TrainOptions o;
  ForEachTrainField(o, [&count](const FieldInfo&, const auto&) { ++count; });
  return count;
}

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_TRAIN_TRAIN_FIELDS_H_
