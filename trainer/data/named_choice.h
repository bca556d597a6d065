// Every choice a setting offers is an enum with one name table: the flag's accepted values, its
// --help, config.json and every error message read that table, so a name is written once.
//
// A choice enum E specialises ChoiceNames<E> with `what` (how messages name the choice) and
// `names`, the spelling of each enumerator in declaration order (enumerators count from 0).
// An empty name marks "not chosen" (ProceduralScene::kNone): it is stored, never typed.
#ifndef ECRF_TRAINER_DATA_NAMED_CHOICE_H_
#define ECRF_TRAINER_DATA_NAMED_CHOICE_H_

#include <cstddef>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace ecrf::trainer {

template <class E>
struct ChoiceNames;  // specialised next to each choice enum

// A type with a name table.
template <class E, class = void>
struct IsNamedChoice : std::false_type {};
template <class E>
struct IsNamedChoice<E, std::void_t<decltype(ChoiceNames<E>::names)>> : std::true_type {};

template <class E>
const char* NameOf(E value) {
  const auto& names = ChoiceNames<E>::names;
  const size_t index = static_cast<size_t>(value);
  return index < std::size(names) ? names[index] : "?";
}

// The names a user may type, in table order.
template <class E>
std::vector<std::string> TypedNames() {
  std::vector<std::string> typed;
  for (const char* name : ChoiceNames<E>::names) {
    if (*name) typed.emplace_back(name);
  }
  return typed;
}

// "auto, object, unbounded or forward": the list every message about the choice shows.
template <class E>
std::string NameList() {
  const std::vector<std::string> typed = TypedNames<E>();
  std::string list;
  for (size_t k = 0; k < typed.size(); ++k) {
    list += (k == 0 ? "" : k + 1 == typed.size() ? " or " : ", ") + typed[k];
  }
  return list;
}

// The enumerator named `name` (the empty name included, for stored values). Throws
// std::invalid_argument "WHERE: unknown WHAT 'NAME' (the list)".
template <class E>
E ChoiceFromName(const std::string& name, const std::string& where) {
  const auto& names = ChoiceNames<E>::names;
  for (size_t k = 0; k < std::size(names); ++k) {
    if (name == names[k]) return static_cast<E>(k);
  }
  throw std::invalid_argument(where + ": unknown " + ChoiceNames<E>::what + " '" + name + "' (" +
                              NameList<E>() + ")");
}

// auto / on / off: features whose default depends on the scene (exposure codes, refined cameras).
enum class Toggle { kAuto, kOn, kOff };
template <>
struct ChoiceNames<Toggle> {
  static constexpr const char* what = "value";
  static constexpr const char* names[] = {"auto", "on", "off"};
};

// Whether a Toggle is on, given what auto means here.
inline bool IsOn(Toggle t, bool auto_means_on) {
  return t == Toggle::kOn || (t == Toggle::kAuto && auto_means_on);
}

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_DATA_NAMED_CHOICE_H_
