// Every field of the settings table (trainer/train/train_fields.def) survives each path that
// carries settings: config.json, the checkpoint and the command line. The tests walk the table,
// so a field added to it is checked here without a line of its own; FieldsLost's own test shows
// that a path forgetting one field is caught.
#include <gtest/gtest.h>
#include <unistd.h>

#include <functional>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "tests/common/invoke.h"
#include "tests/common/scoped_temp_dir.h"
#include "tests/common/small_model.h"
#include "tools/commands.h"
#include "tools/train_field_text.h"
#include "tools/train_flags.h"
#include "trainer/train/train_config.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {
namespace {

using trainer::FieldInfo;
using trainer::FieldKind;
using trainer::FlagText;
using trainer::TrainOptions;

// A value the field admits other than v.
template <class T>
T OtherValue(const FieldInfo& info, const T& v) {
  if constexpr (trainer::IsNamedChoice<T>::value) {
    const size_t count = std::size(trainer::ChoiceNames<T>::names);
    size_t next = (size_t(v) + 1) % count;
    if (!*trainer::ChoiceNames<T>::names[next]) next = (next + 1) % count;  // typed names only
    return T(next);
  } else if constexpr (std::is_same_v<T, std::string>) {
    return v + "/other";
  } else if constexpr (std::is_same_v<T, bool>) {
    return !v;
  } else if constexpr (std::is_same_v<T, std::vector<int>>) {
    return {7, 19, 23};
  } else if constexpr (std::is_same_v<T, std::vector<float>>) {
    return {0.25f, 0.625f};
  } else if constexpr (std::is_same_v<T, trainer::Shape3>) {
    return info.text == FlagText::kLineBlock ? T{1, 4, 16} : T{4, 8, 32};
  } else if (info.text == FlagText::kGridEdge) {
    const long edge = std::lround(std::cbrt(double(v))) + 1;
    return T(edge * edge * edge);
  } else if (info.text == FlagText::kSize) {
    return T(v + 123456);
  } else {
    const trainer::Limits& l = info.limits;
    const double hi = l.any || l.hi >= 1e300 ? double(v) * 2 + 3 : l.hi;
    const double lo = l.any ? double(v) - 3 : l.lo;
    // Inside the limits, away from open ends, and not v.
    T other = std::is_integral_v<T> ? T(v + 1 <= hi ? v + 1 : v - 1) : T(lo + (hi - lo) * 0.375);
    if (other == v) other = T(lo + (hi - lo) * 0.625);
    return other;
  }
}

// The field `key` of o, as text (FieldText is exact: it reads back as the same value).
std::string FieldOf(const TrainOptions& o, const std::string& key) {
  std::string text = "(no such field)";
  trainer::ForEachTrainField(o, [&](const FieldInfo& info, const auto& v) {
    if (key == info.key) text = FieldText(info, v);
  });
  return text;
}

const TrainOptions kDefaults;

using Path = std::function<TrainOptions(const TrainOptions& changed, const FieldInfo& info)>;

// For each field `carried` selects, a copy of the `fast` options with that field changed, sent
// through `path`: the names of the fields whose change did not come back.
std::vector<std::string> FieldsLost(const Path& path,
                                    const std::function<bool(const FieldInfo&)>& carried) {
  const TrainOptions base = trainer::PresetOptions(trainer::Preset::kFast);
  std::vector<std::string> lost;
  trainer::ForEachTrainField(base, [&](const FieldInfo& info, const auto& value) {
    if (!carried(info)) return;
    const auto other = OtherValue(info, value);
    EXPECT_EQ(trainer::FieldProblem(info, other), "") << info.key << ": the test broke a limit";
    TrainOptions changed = base;
    trainer::ForEachTrainField(changed, [&](const FieldInfo& field, auto& v) {
      if constexpr (std::is_same_v<std::decay_t<decltype(v)>, std::decay_t<decltype(value)>>) {
        if (field.key == info.key) v = other;
      }
    });
    const std::string want = FieldOf(changed, info.key);
    EXPECT_NE(want, FieldOf(base, info.key)) << info.key << ": the test changed nothing";
    if (FieldOf(path(changed, info), info.key) != want) lost.push_back(info.key);
  });
  return lost;
}

bool Recorded(const FieldInfo& info) {
  return info.kind == FieldKind::kSetting || info.kind == FieldKind::kBookkeeping;
}
bool IsFlag(const FieldInfo& info) { return info.flag != nullptr; }

TrainOptions ThroughConfigJson(const TrainOptions& o, const FieldInfo&) {
  return trainer::TrainConfigFromJson(trainer::TrainConfigToJson(o), "config.json");
}

TEST(TrainFields, EveryRecordedFieldRoundTripsThroughConfigJson) {
  EXPECT_EQ(FieldsLost(ThroughConfigJson, Recorded), std::vector<std::string>{});
}

TEST(TrainFields, EveryRecordedFieldRoundTripsThroughTheCheckpoint) {
  testing_util::ScopedTempDir dir("train_fields");
  const std::string path = dir.path() + "/checkpoint.ckpt";
  trainer::TensorfModel model = testing_models::DenseSmallModel();
  auto through_checkpoint = [&](const TrainOptions& o, const FieldInfo&) {
    trainer::SaveModelCheckpoint(path, model, 1, o, nullptr, nullptr, &o);
    const trainer::CheckpointRunInfo info = trainer::ReadCheckpointRunInfo(path);
    EXPECT_TRUE(info.has_config);
    return info.config;
  };
  EXPECT_EQ(FieldsLost(through_checkpoint, Recorded), std::vector<std::string>{});
}

TEST(TrainFields, EveryFlagOfTheTableSetsItsField) {
  auto through_flags = [](const TrainOptions& o, const FieldInfo& info) {
    std::vector<std::string> args = {"--preset", "fast", info.flag};
    trainer::ForEachTrainField(o, [&](const FieldInfo& field, const auto& v) {
      if (field.key != info.key) return;
      if constexpr (!std::is_same_v<std::decay_t<decltype(v)>, bool>) {
        args.push_back(FieldText(info, v));
      }
    });
    if (std::string(info.key) == "preset") args.erase(args.begin(), args.begin() + 2);
    return ResolveTrainOptions(args);
  };
  EXPECT_EQ(FieldsLost(through_flags, IsFlag), std::vector<std::string>{});
}

TEST(TrainFields, ACheckThatCannotSeeAForgottenFieldFails) {
  // A config path that drops one field, as a hand-kept visitor missing a line did.
  auto forgetful = [](const TrainOptions& o, const FieldInfo&) {
    nlohmann::json j = nlohmann::json::parse(trainer::TrainConfigToJson(o));
    j["settings"].erase("mlp_hidden");
    j["bookkeeping"].erase("eval_every");
    return trainer::TrainConfigFromJson(j.dump(), "forgetful");
  };
  EXPECT_EQ(FieldsLost(forgetful, Recorded),
            (std::vector<std::string>{"mlp_hidden", "eval_every"}));
  // A path that carries nothing loses every field it is asked about.
  auto nothing = [](const TrainOptions&, const FieldInfo&) {
    return trainer::PresetOptions(trainer::Preset::kFast);
  };
  size_t flags = 0;
  trainer::ForEachTrainField(kDefaults,
                             [&](const FieldInfo& info, const auto&) { flags += IsFlag(info); });
  EXPECT_EQ(FieldsLost(nothing, IsFlag).size(), flags);
}

TEST(TrainFields, ConfigJsonHoldsEveryRecordedFieldAndNoOther) {
  const nlohmann::json j = nlohmann::json::parse(trainer::TrainConfigToJson(TrainOptions()));
  size_t recorded = 0;
  trainer::ForEachTrainField(kDefaults, [&](const FieldInfo& info, const auto&) {
    if (!Recorded(info)) {
      EXPECT_FALSE(j["settings"].contains(info.key) || j["bookkeeping"].contains(info.key))
          << info.key << " is about one command and must not be recorded";
      return;
    }
    ++recorded;
    const char* section = info.kind == FieldKind::kSetting ? "settings" : "bookkeeping";
    EXPECT_TRUE(j[section].contains(info.key)) << info.key << " missing from " << section;
  });
  EXPECT_EQ(j["settings"].size() + j["bookkeeping"].size(), recorded);
}

TEST(TrainFields, PresetsAndRatePointsAreDataTheTableAdmits) {
  for (const std::string& preset : trainer::TypedNames<trainer::Preset>()) {
    const TrainOptions p = trainer::PresetOptions(preset);
    EXPECT_STREQ(trainer::NameOf(p.preset), preset.c_str());
    for (const std::string& rate : trainer::TypedNames<trainer::RatePoint>()) {
      TrainOptions o = p;
      trainer::ApplyRatePoint(rate, &o);
      EXPECT_NO_THROW(trainer::CheckTrainFields(o, preset + " " + rate));
    }
  }
  EXPECT_EQ(trainer::PresetOptions("fast").iters, 3000);
  EXPECT_EQ(trainer::PresetOptions("tiny").plane_block, (trainer::Shape3{8, 16, 16}));
  TrainOptions o;
  EXPECT_THROW(trainer::ApplySettingsJson(R"({"itres": 3000})", "preset", &o),
               std::invalid_argument);
  EXPECT_THROW(trainer::PresetOptions("quick"), std::invalid_argument);
  // A config.json with a value its line does not admit is refused, naming the field.
  nlohmann::json j = nlohmann::json::parse(trainer::TrainConfigToJson(TrainOptions()));
  j["settings"]["rate_start"] = 1.5;
  try {
    trainer::TrainConfigFromJson(j.dump(), "run/config.json");
    ADD_FAILURE() << "accepted rate_start 1.5";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'rate_start' 1.5 is not in [0, 1)"), std::string::npos)
        << e.what();
  }
}

TEST(TrainFields, HelpListsEveryFlagOfTheTable) {
  testing::internal::CaptureStdout();
  EXPECT_EQ(testing_cli::Invoke(RunTrain, {"train", "--help"}), 0);
  const std::string help = testing::internal::GetCapturedStdout();
  trainer::ForEachTrainField(kDefaults, [&](const FieldInfo& info, const auto&) {
    if (info.flag)
      EXPECT_NE(help.find(std::string(info.flag) + " "), std::string::npos) << info.flag;
  });
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
