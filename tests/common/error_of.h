// The message of the std::runtime_error an action throws ("" when it throws none), for tests of
// error texts.
#ifndef ECRF_TESTS_COMMON_ERROR_OF_H_
#define ECRF_TESTS_COMMON_ERROR_OF_H_

#include <functional>
#include <stdexcept>
#include <string>

namespace ecrf {
namespace testing_errors {

inline std::string ErrorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "";
}

inline bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace testing_errors
}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_ERROR_OF_H_
