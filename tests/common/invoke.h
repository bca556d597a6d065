// Runs an `ecrf` subcommand in-process with the given argv (argv[0] is the subcommand's name).
#ifndef ECRF_TESTS_COMMON_INVOKE_H_
#define ECRF_TESTS_COMMON_INVOKE_H_

#include <string>
#include <vector>

namespace ecrf {
namespace testing_cli {

inline int Invoke(int (*command)(int, char**), std::vector<std::string> args) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return command(int(argv.size()), argv.data());
}

}  // namespace testing_cli
}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_INVOKE_H_
