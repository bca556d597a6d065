// What the table of training settings (train_fields.def) says about each field besides its type
// and default: whether a run records it, its flag, the values it admits and its help. Written as
// a chain, e.g. Setting(kSchedule).Flag("--iters", "N").In(1, 100000000).Help("iterations"), so
// that each line of the table reads as a sentence.
#ifndef ECRF_TRAINER_TRAIN_TRAIN_FIELD_INFO_H_
#define ECRF_TRAINER_TRAIN_TRAIN_FIELD_INFO_H_

#include <array>

namespace ecrf::trainer {

// What a run does with a field.
enum class FieldKind {
  kSetting,      // changes what a run trains or writes: recorded; --resume refuses a change
  kBookkeeping,  // where a run writes and how it is scored: recorded, free to change
  kCommand,      // about this invocation only (--resume, --overwrite): never recorded
  kInternal,     // set by code for one pass (the camera warm-up): neither a flag nor recorded
};

// The --help section of a flag.
enum class FlagGroup { kData, kSchedule, kRate, kRun };
inline constexpr const char* kFlagGroupTitles[] = {
    "Data", "Schedule and model", "ECRF objective (defaults: the chosen rate point)",
    "Evaluation and bookkeeping (no effect on the file)"};

// How a flag's text maps to the field, where it is not the plain number, name or path.
enum class FlagText {
  kPlain,       // the number, choice name, path or (for bool fields) a switch
  kIterations,  // "I,J,...": increasing positive iterations
  kShares,      // "F,G,...": increasing shares in (0, 1); "" is the empty list
  kPlaneBlock,  // "CxHxW": powers of two <= 32
  kLineBlock,   // "CxL" for the last two entries of {1, C, L}
  kSize,        // bytes, with a unit ("500KB")
  kGridEdge,    // N for N^3 voxels
  kAutoNumber,  // a number in the limits, or "auto" for the field's negative default
};

// The values a number admits: lo < / <= v < / <= hi (open ends exclude the bound).
struct Limits {
  bool any = true;
  double lo = 0, hi = 0;
  bool lo_open = false, hi_open = false;
};

struct FieldInfo {
  FieldKind kind = FieldKind::kSetting;
  FlagGroup group = FlagGroup::kSchedule;
  const char* flag = nullptr;   // nullptr: not a flag (NoFlag says why)
  const char* value_name = "";  // --help's placeholder: "N", "W", "DIR"
  const char* help = "";
  Limits limits;
  FlagText text = FlagText::kPlain;
  const char* key = "";  // the field's name: config.json's key (set by the table)

  constexpr FieldInfo Flag(const char* name, const char* value = "") const {
    FieldInfo f = *this;
    f.flag = name;
    f.value_name = value;
    return f;
  }
  // Not a flag; `why` is for the reader of the table (a preset's property, a compound flag's).
  constexpr FieldInfo NoFlag(const char* /*why*/) const { return *this; }
  constexpr FieldInfo Help(const char* text_) const {
    FieldInfo f = *this;
    f.help = text_;
    return f;
  }
  constexpr FieldInfo Text(FlagText t) const {
    FieldInfo f = *this;
    f.text = t;
    return f;
  }
  constexpr FieldInfo Bounded(double lo, double hi, bool lo_open, bool hi_open) const {
    FieldInfo f = *this;
    f.limits = Limits{false, lo, hi, lo_open, hi_open};
    return f;
  }
  constexpr FieldInfo In(double lo, double hi) const { return Bounded(lo, hi, false, false); }
  constexpr FieldInfo InOpenClosed(double lo, double hi) const {
    return Bounded(lo, hi, true, false);
  }
  constexpr FieldInfo InClosedOpen(double lo, double hi) const {
    return Bounded(lo, hi, false, true);
  }
  constexpr FieldInfo AtLeast(double lo) const { return Bounded(lo, 1e300, false, false); }
  constexpr FieldInfo Above(double lo) const { return Bounded(lo, 1e300, true, false); }
  constexpr FieldInfo Named(const char* name) const {
    FieldInfo f = *this;
    f.key = name;
    return f;
  }
};

// A field of `kind` shown under `group` in --help; the builders above add the rest. (Assigned,
// not aggregate-initialised, so that the members left at their defaults draw no warning.)
constexpr FieldInfo Field(FieldKind kind, FlagGroup group) {
  FieldInfo f;
  f.kind = kind;
  f.group = group;
  return f;
}
constexpr FieldInfo DataSetting() { return Field(FieldKind::kSetting, FlagGroup::kData); }
constexpr FieldInfo ScheduleSetting() { return Field(FieldKind::kSetting, FlagGroup::kSchedule); }
constexpr FieldInfo RateSetting() { return Field(FieldKind::kSetting, FlagGroup::kRate); }
constexpr FieldInfo Bookkeeping() { return Field(FieldKind::kBookkeeping, FlagGroup::kRun); }
constexpr FieldInfo Command() { return Field(FieldKind::kCommand, FlagGroup::kRun); }
constexpr FieldInfo Internal() { return Field(FieldKind::kInternal, FlagGroup::kRun); }

// The block shapes of the rate term: channel x H x W for planes, 1 x channel x L for lines.
using Shape3 = std::array<int, 3>;

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_TRAIN_TRAIN_FIELD_INFO_H_
