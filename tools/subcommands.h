// Commands made of subcommands (`ecrf`, `ecrf report`, `ecrf bench`): one table gives the list in
// the usage, `NAME ...` runs one, `help NAME ...` shows its help (the same as `NAME ... --help`),
// and a misspelt name gets the nearest one as a suggestion, as unknown flags do (tools/cli.h).
#ifndef ECRF_TOOLS_SUBCOMMANDS_H_
#define ECRF_TOOLS_SUBCOMMANDS_H_

#include <string>
#include <vector>

namespace ecrf {
namespace tools {

struct Subcommand {
  std::string name;
  int (*run)(int argc, char** argv);  // argv[0] is the subcommand's name; returns the exit code
  std::string summary;                // for the list; "\n" starts an indented line
};

struct SubcommandTable {
  std::string command;  // "ecrf report": in the usage and the error messages
  std::string kind;     // "command", "report", "benchmark": what a subcommand is called
  std::vector<Subcommand> subcommands;
  std::string footer;  // after the list
};

// The usage: "usage: COMMAND <KIND> [options]", the list, the footer.
std::string SubcommandUsage(const SubcommandTable& table);

// The subcommand whose name is that argument, or nullptr.
const Subcommand* FindSubcommand(const SubcommandTable& table, const std::string& name);

// argv[0] is the command's name, argv[1] the subcommand's (or -h, --help, help [NAME ...]).
// Returns the subcommand's exit code; 0 after help, 2 (one line on stderr, the usage when nothing
// was given) when there is no such subcommand. Exceptions from the subcommand pass through.
int RunSubcommand(const SubcommandTable& table, int argc, char** argv);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_SUBCOMMANDS_H_
