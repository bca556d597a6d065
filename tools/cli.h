// Command-line parsing for every `ecrf` command, on CLI11: each command declares its flags once
// (name, type, range, default, help) and this file gives them one behaviour everywhere:
//   - `--help` prints the command's help (with the defaults a run would use) and never runs it;
//   - an unknown flag is one short line: the flag, the nearest known one, and where help is;
//   - sizes take explicit units (a bare number is refused with the fix in the message);
//   - `--threads` means the same in every command (0 or absent: all cores).
#ifndef ECRF_TOOLS_CLI_H_
#define ECRF_TOOLS_CLI_H_

#include <CLI/CLI.hpp>
#include <cstddef>
#include <string>
#include <vector>

namespace ecrf {
namespace tools {

// A command's parser with ecrf's conventions: "ecrf NAME" in the usage line, -h/--help, a
// description, wide enough columns for our flag names.
std::unique_ptr<CLI::App> MakeCommand(const std::string& name, const std::string& description);

// Parses argv (argv[0] is the command's name). Returns -1 when the command should run, otherwise
// the exit code after printing: 0 after --help, 2 after an error (one short line on stderr).
int ParseCommandLine(CLI::App* app, int argc, char** argv);

// A usage error found after parsing (a value out of range, a size without a unit): the same one
// line as a parse error, exit code 2.
int UsageError(const CLI::App& app, const std::string& message);

// The same on a list of arguments (without the command's name), for commands that resolve a
// command line more than once (the sweep) and for tests. Throws std::invalid_argument with the
// short message on errors; returns false after --help (help printed to stdout).
bool ParseArguments(CLI::App* app, std::vector<std::string> args);

// The name among `names` nearest to `unknown` by edit distance, or "" when none is close (within
// a third of its length, at least 2 edits): the "did you mean" of every error.
std::string NearestName(const std::string& unknown, const std::vector<std::string>& names);

// The known flag nearest to an unknown one (edit distance), or "" when none is close.
std::string NearestFlag(const CLI::App& app, const std::string& unknown);

// "500KB", "1.2MB", "300000B", "64KiB": bytes. A bare number is refused ("500" could be bytes or
// kilobytes: the message says how to write either). Throws std::invalid_argument naming flag.
size_t ParseSizeWithUnit(const std::string& flag, const std::string& text);

// A flag that was renamed: giving old_name fails with one line naming new_name (hidden in --help).
void AddRenamedFlag(CLI::App* app, const std::string& old_name, const std::string& new_name);

// --threads N on app, stored into *threads (0 = all cores); ApplyThreads sets OpenMP's count.
CLI::Option* AddThreadsFlag(CLI::App* app, int* threads);
void ApplyThreads(int threads);
// The number of threads `--threads 0` stands for on this machine.
int AllCores();

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_CLI_H_
