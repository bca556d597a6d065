// The text of a training setting on the command line, from its line in train_fields.def: what a
// flag accepts (ParseFieldText) and what --help shows as its default (FieldText). The two are
// inverses: FieldText's output parses back to the same value.
#ifndef ECRF_TOOLS_TRAIN_FIELD_TEXT_H_
#define ECRF_TOOLS_TRAIN_FIELD_TEXT_H_

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "trainer/train/train_field_check.h"

namespace ecrf::tools {

// The shortest decimal that reads back as the same float or double.
std::string ShortestDecimal(double v, bool single_precision);
// Strict conversions: the whole text, or std::invalid_argument "'TEXT' is not ...".
long long ParseWholeNumber(const std::string& text);
double ParseRealNumber(const std::string& text);
std::vector<int> ParseIntList(const std::string& text);           // "I,J,..."
std::vector<float> ParseFloatList(const std::string& text);       // "F,G,..."; "" is empty
std::vector<int> ParseShapeText(const std::string& text, int n);  // "AxBxC"
std::string JoinText(const std::vector<int>& v, const char* separator);
size_t ParseByteSize(const std::string& flag, const std::string& text);  // "500KB"

template <class T>
std::string FieldText(const trainer::FieldInfo& info, const T& v) {
  using trainer::FlagText;
  if constexpr (trainer::IsNamedChoice<T>::value) {
    return trainer::NameOf(v);
  } else if constexpr (std::is_same_v<T, std::string>) {
    return v;
  } else if constexpr (std::is_same_v<T, bool>) {
    return v ? "true" : "false";
  } else if constexpr (std::is_same_v<T, std::vector<int>>) {
    return JoinText(v, ",");
  } else if constexpr (std::is_same_v<T, std::vector<float>>) {
    std::string s;
    for (size_t k = 0; k < v.size(); ++k) s += (k ? "," : "") + ShortestDecimal(v[k], true);
    return s;
  } else if constexpr (std::is_same_v<T, trainer::Shape3>) {
    if (info.text == FlagText::kLineBlock) return JoinText({v[1], v[2]}, "x");
    return JoinText({v[0], v[1], v[2]}, "x");
  } else {
    if (info.text == FlagText::kGridEdge) return std::to_string(std::lround(std::cbrt(double(v))));
    if (info.text == FlagText::kSize) return std::to_string(v) + "B";
    if (info.text == FlagText::kAutoNumber && v < 0) return "auto";
    if constexpr (std::is_floating_point_v<T>) return ShortestDecimal(v, sizeof(T) == 4);
    return std::to_string(v);
  }
}

// Reads a flag's text into *v; throws std::invalid_argument "FLAG: 'TEXT' PROBLEM".
template <class T>
void ParseFieldText(const trainer::FieldInfo& info, const std::string& text, T* v) {
  using trainer::FlagText;
  const std::string flag = info.flag ? info.flag : info.key;
  T value{};
  try {
    if constexpr (trainer::IsNamedChoice<T>::value) {
      value = trainer::ChoiceFromName<T>(text, flag);
      if (text.empty()) throw std::invalid_argument("'' is no " + std::string(flag) + " value");
    } else if constexpr (std::is_same_v<T, std::string>) {
      value = text;
    } else if constexpr (std::is_same_v<T, bool>) {
      value = ParseWholeNumber(text == "true" ? "1" : text == "false" ? "0" : text) != 0;
    } else if constexpr (std::is_same_v<T, std::vector<int>>) {
      value = ParseIntList(text);
    } else if constexpr (std::is_same_v<T, std::vector<float>>) {
      value = ParseFloatList(text);
    } else if constexpr (std::is_same_v<T, trainer::Shape3>) {
      const bool line = info.text == FlagText::kLineBlock;
      const std::vector<int> s = ParseShapeText(text, line ? 2 : 3);
      value = line ? T{1, s[0], s[1]} : T{s[0], s[1], s[2]};
    } else if (info.text == FlagText::kSize) {
      value = T(ParseByteSize(flag, text));
    } else if (info.text == FlagText::kAutoNumber && text == "auto") {
      value = T(-1);
    } else if constexpr (std::is_floating_point_v<T>) {
      value = T(ParseRealNumber(text));
    } else {
      const long long n = ParseWholeNumber(text);
      const double edge = double(n);
      if (info.text == FlagText::kGridEdge) {
        const std::string problem = trainer::LimitsProblem(info.limits, edge);
        if (!problem.empty()) throw std::invalid_argument("'" + text + "' " + problem);
        value = T(n * n * n);
      } else {
        const std::string problem = trainer::LimitsProblem(info.limits, edge);
        if (!problem.empty()) throw std::invalid_argument("'" + text + "' " + problem);
        value = T(n);
      }
    }
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    // Messages that name the flag already (a choice, a size) stay as they are.
    throw std::invalid_argument(what.rfind(flag, 0) == 0 ? what : flag + ": " + what);
  }
  const std::string problem = trainer::FieldProblem(info, value);
  if (!problem.empty()) throw std::invalid_argument(flag + ": '" + text + "' " + problem);
  *v = value;
}

}  // namespace ecrf::tools

#endif  // ECRF_TOOLS_TRAIN_FIELD_TEXT_H_
