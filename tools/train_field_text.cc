#include "tools/train_field_text.h"

#include <cerrno>
#include <cstdio>
#include <cstdlib>

#include "tools/cli.h"

namespace ecrf::tools {

std::string ShortestDecimal(double v, bool single_precision) {
  char text[40];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(text, sizeof(text), "%.*g", digits, v);
    const double back = std::strtod(text, nullptr);
    if (single_precision ? float(back) == float(v) : back == v) break;
  }
  return text;
}

long long ParseWholeNumber(const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || errno || *end)
    throw std::invalid_argument("'" + text + "' is not an integer");
  return v;
}

double ParseRealNumber(const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || errno || *end || !std::isfinite(v))
    throw std::invalid_argument("'" + text + "' is not a number");
  return v;
}

namespace {

std::vector<std::string> SplitText(const std::string& text, char separator) {
  std::vector<std::string> parts;
  for (size_t begin = 0; begin <= text.size();) {
    size_t end = text.find(separator, begin);
    if (end == std::string::npos) end = text.size();
    parts.push_back(text.substr(begin, end - begin));
    begin = end + 1;
  }
  return parts;
}

}  // namespace

std::vector<int> ParseIntList(const std::string& text) {
  std::vector<int> v;
  for (const std::string& part : SplitText(text, ',')) {
    const long long n = ParseWholeNumber(part);
    if (n < -2147483647LL || n > 2147483647LL)
      throw std::invalid_argument("'" + part + "' is out of range");
    v.push_back(int(n));
  }
  return v;
}

std::vector<float> ParseFloatList(const std::string& text) {
  std::vector<float> v;
  if (text.empty()) return v;
  for (const std::string& part : SplitText(text, ',')) v.push_back(float(ParseRealNumber(part)));
  return v;
}

std::vector<int> ParseShapeText(const std::string& text, int n) {
  const std::vector<std::string> parts = SplitText(text, 'x');
  if (int(parts.size()) != n) {
    throw std::invalid_argument("'" + text + "' is not " + std::to_string(n) +
                                " powers of two <= 32 joined by 'x'");
  }
  std::vector<int> shape;
  for (const std::string& part : parts) shape.push_back(int(ParseWholeNumber(part)));
  return shape;
}

std::string JoinText(const std::vector<int>& v, const char* separator) {
  std::string s;
  for (size_t k = 0; k < v.size(); ++k) s += (k ? separator : "") + std::to_string(v[k]);
  return s;
}

size_t ParseByteSize(const std::string& flag, const std::string& text) {
  return ParseSizeWithUnit(flag, text);
}

}  // namespace ecrf::tools
