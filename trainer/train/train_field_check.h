// Which values a training setting admits, from its line in train_fields.def: the same rule for
// a flag, a config.json being read back and a preset.
#ifndef ECRF_TRAINER_TRAIN_TRAIN_FIELD_CHECK_H_
#define ECRF_TRAINER_TRAIN_TRAIN_FIELD_CHECK_H_

#include <cmath>
#include <cstdio>
#include <string>
#include <type_traits>
#include <vector>

#include "trainer/train/train_fields.h"

namespace ecrf::trainer {

// "[0, 1)", "(0, 0.5]", ">= 0", "> 0": how messages and --help state limits.
std::string LimitsText(const Limits& limits);

// "" when the limits admit v, else why not ("is not in [0, 1)").
std::string LimitsProblem(const Limits& limits, double v);

// "" when `value` is one the field admits, else why not, e.g. "is not in [0, 1)" or "is not
// increasing positive iterations"; for a kGridEdge field the limits bound the cube's edge.
template <class T>
std::string FieldProblem(const FieldInfo& info, const T& value) {
  if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
    if constexpr (std::is_floating_point_v<T>) {
      if (!std::isfinite(value)) return "is not a finite number";
      if (info.text == FlagText::kAutoNumber && value < 0) return "";  // auto
    }
    const double v = info.text == FlagText::kGridEdge ? std::cbrt(double(value)) : double(value);
    return info.limits.any ? "" : LimitsProblem(info.limits, v);
  } else if constexpr (std::is_same_v<T, std::vector<int>>) {
    for (size_t k = 0; k < value.size(); ++k) {
      if (value[k] < 1 || (k > 0 && value[k] <= value[k - 1]))
        return "is not increasing positive iterations";
    }
  } else if constexpr (std::is_same_v<T, std::vector<float>>) {
    for (size_t k = 0; k < value.size(); ++k) {
      if (!(value[k] > 0.f && value[k] < 1.f) || (k > 0 && !(value[k] > value[k - 1])))
        return "is not a list of increasing shares in (0, 1)";
    }
  } else if constexpr (std::is_same_v<T, Shape3>) {
    for (int k = 0; k < 3; ++k) {
      const int n = value[size_t(k)];
      if (n < 1 || n > 32 || (n & (n - 1)) != 0) return "is not powers of two <= 32";
    }
    if (info.text == FlagText::kLineBlock && value[0] != 1) return "does not start with 1";
  }
  return "";
}

// Throws std::invalid_argument "WHERE: setting 'KEY' ... PROBLEM" for the first field of o that
// its line does not admit.
void CheckTrainFields(const TrainOptions& o, const std::string& where);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_TRAIN_TRAIN_FIELD_CHECK_H_
