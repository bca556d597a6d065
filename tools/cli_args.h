// Argument parsing shared by the subcommands: each throws std::invalid_argument naming the flag
// and the value, which main() turns into "ecrf CMD: error: ..." and exit code 1.
#ifndef ECRF_TOOLS_CLI_ARGS_H_
#define ECRF_TOOLS_CLI_ARGS_H_

#include <string>

namespace ecrf {
namespace tools {

float ParseFloat(const char* flag, const char* value);  // non-negative
int ParseInt(const char* flag, const char* value);      // non-negative
// "16x16x16" or "8x8" into n values, each a power of two <= 32.
void ParseShape(const char* flag, const std::string& text, int n, int* out);
// The value after flag argv[*i] (advancing *i); throws if the command line ends there.
const char* FlagValue(int argc, char** argv, int* i);
bool IsDirectory(const std::string& path);
bool FileExists(const std::string& path);  // any kind of file
// Creates a directory and its missing parents (an existing directory is fine).
void MakeDirectory(const std::string& dir);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_CLI_ARGS_H_
