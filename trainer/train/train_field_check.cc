#include "trainer/train/train_field_check.h"

#include <nlohmann/json.hpp>
#include <stdexcept>

namespace ecrf::trainer {
namespace {

std::string Number(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.12g", v);
  return text;
}

}  // namespace

std::string LimitsText(const Limits& l) {
  if (l.any) return "";
  if (l.hi >= 1e300) return (l.lo_open ? "> " : ">= ") + Number(l.lo);
  return (l.lo_open ? "(" : "[") + Number(l.lo) + ", " + Number(l.hi) + (l.hi_open ? ")" : "]");
}

std::string LimitsProblem(const Limits& l, double v) {
  if (l.any) return "";
  const bool above_lo = l.lo_open ? v > l.lo : v >= l.lo;
  const bool below_hi = l.hi_open ? v < l.hi : v <= l.hi;
  if (above_lo && below_hi) return "";
  return l.hi >= 1e300 ? "is not " + LimitsText(l) : "is not in " + LimitsText(l);
}

void CheckTrainFields(const TrainOptions& o, const std::string& where) {
  ForEachTrainField(o, [&where](const FieldInfo& info, const auto& value) {
    const std::string problem = FieldProblem(info, value);
    if (problem.empty()) return;
    std::string shown;
    if constexpr (IsNamedChoice<std::decay_t<decltype(value)>>::value) {
      shown = NameOf(value);
    } else {
      shown = nlohmann::json(value).dump();
    }
    throw std::invalid_argument(where + ": setting '" + info.key + "' " + shown + " " + problem);
  });
}

}  // namespace ecrf::trainer
