#include "trainer/train/train_config.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <type_traits>

#include "trainer/train/train_field_check.h"
#include "trainer/train/train_fields.h"

namespace ecrf {
namespace trainer {
namespace {

using Json = nlohmann::json;

bool Recorded(const FieldInfo& info) {
  return info.kind == FieldKind::kSetting || info.kind == FieldKind::kBookkeeping;
}

// The shortest decimal that reads back as the same float: config.json says 3e-11, not
// 2.9999999848243206e-11, and reading it back gives the identical float.
Json FloatJson(float v) {
  char text[32];
  for (int digits = 1; digits <= 9; ++digits) {
    std::snprintf(text, sizeof(text), "%.*g", digits, double(v));
    if (std::strtof(text, nullptr) == v) break;
  }
  return Json::parse(text);
}

template <class T>
Json ValueJson(const T& v) {
  if constexpr (std::is_same_v<T, float>) {
    return FloatJson(v);
  } else if constexpr (IsNamedChoice<T>::value) {
    return NameOf(v);
  } else {
    return Json(v);
  }
}

// Reads j into *v; throws std::runtime_error naming `where` and the field.
template <class T>
void ReadValue(const Json& j, const std::string& where, const FieldInfo& info, T* v) {
  const std::string field = where + ": config field '" + info.key + "'";
  try {
    if constexpr (IsNamedChoice<T>::value) {
      *v = ChoiceFromName<T>(j.get<std::string>(), field);
    } else if constexpr (std::is_same_v<T, Shape3>) {
      const std::vector<int> shape = j.get<std::vector<int>>();
      if (shape.size() != 3) throw std::runtime_error(field + " is not 3 integers");
      for (size_t k = 0; k < 3; ++k) (*v)[k] = shape[k];
    } else {
      j.get_to(*v);
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(field + ": " + e.what());
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
}

// The recorded fields of `kind` from `in` into o; fields `in` lacks keep their values.
void ReadFields(const Json& in, FieldKind kind, const std::string& where, TrainOptions* o) {
  ForEachTrainField(*o, [&](const FieldInfo& info, auto& value) {
    if (info.kind == kind && in.contains(info.key)) ReadValue(in.at(info.key), where, info, &value);
  });
}

Json ToJson(const TrainOptions& o) {
  Json settings = Json::object(), bookkeeping = Json::object();
  ForEachTrainField(o, [&](const FieldInfo& info, const auto& value) {
    if (!Recorded(info)) return;
    (info.kind == FieldKind::kSetting ? settings : bookkeeping)[info.key] = ValueJson(value);
  });
  return Json{{"config_version", kTrainConfigVersion},
              {"settings", settings},
              {"bookkeeping", bookkeeping}};
}

}  // namespace

std::string TrainConfigToJson(const TrainOptions& options, int indent) {
  return ToJson(options).dump(indent);
}

TrainOptions TrainConfigFromJson(const std::string& text, const std::string& where) {
  Json j;
  try {
    j = Json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(where + ": not a run configuration (" + e.what() + ")");
  }
  if (!j.is_object() || !j.contains("settings") || !j["settings"].is_object()) {
    throw std::runtime_error(where + ": not a run configuration (no \"settings\" object)");
  }
  const int version = j.value("config_version", 0);
  if (version > kTrainConfigVersion) {
    throw std::runtime_error(where + ": config_version " + std::to_string(version) +
                             " is newer than this ecrf reads (" +
                             std::to_string(kTrainConfigVersion) + ")");
  }
  const Json& settings = j["settings"];
  Preset preset = Preset::kFast;  // configs written before presets were recorded
  if (settings.contains("preset")) {
    ReadValue(settings["preset"], where, FieldInfo().Named("preset"), &preset);
  }
  TrainOptions o = PresetOptions(preset);
  ReadFields(settings, FieldKind::kSetting, where, &o);
  if (j.contains("bookkeeping") && j["bookkeeping"].is_object()) {
    ReadFields(j["bookkeeping"], FieldKind::kBookkeeping, where, &o);
  }
  try {
    CheckTrainFields(o, where);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  return o;
}

std::vector<std::string> ChangedSettings(const TrainOptions& before, const TrainOptions& after) {
  const Json a = ToJson(before)["settings"], b = ToJson(after)["settings"];
  std::vector<std::string> changed;
  for (auto it = a.begin(); it != a.end(); ++it) {
    const Json& other = b.at(it.key());
    if (*it != other) changed.push_back(it.key() + ": " + it->dump() + " -> " + other.dump());
  }
  return changed;
}

}  // namespace trainer
}  // namespace ecrf

namespace ecrf::trainer {

void ApplySettingsJson(const std::string& text, const std::string& where, TrainOptions* o) {
  const Json j = Json::parse(text);
  for (auto it = j.begin(); it != j.end(); ++it) {
    bool known = false;
    ForEachTrainField(*o, [&](const FieldInfo& info, auto& value) {
      if (it.key() != info.key) return;
      known = true;
      ReadValue(*it, where, info, &value);
    });
    if (!known) throw std::invalid_argument(where + ": no setting named '" + it.key() + "'");
  }
}

}  // namespace ecrf::trainer
