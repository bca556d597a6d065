// Argument parsing shared by the subcommands: each throws std::invalid_argument naming the flag
// and the value, which main() turns into "ecrf CMD: error: ..." and exit code 1.
#ifndef ECRF_TOOLS_CLI_ARGS_H_
#define ECRF_TOOLS_CLI_ARGS_H_

#include <string>
#include <vector>

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
// Creates a directory and its missing parents (an existing directory is fine); the ones it
// created, outermost first, go to *created when given.
void MakeDirectory(const std::string& dir, std::vector<std::string>* created = nullptr);

// An output directory for a long job: created (with its parents) and proved writable by a probe
// file before the work starts, so that a read-only or misnamed -o fails in the first second, not
// after the training. Directories it created and that are still empty when it goes out of scope
// (the job failed before writing anything) are removed again.
class OutputDirectory {
 public:
  explicit OutputDirectory(const std::string& dir);
  ~OutputDirectory();
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;

 private:
  std::vector<std::string> created_;
};

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_CLI_ARGS_H_
