#include "tools/subcommands.h"

#include <algorithm>
#include <cstdio>

#include "tools/cli.h"

namespace ecrf {
namespace tools {
namespace {

bool IsHelpFlag(const std::string& a) { return a == "--help" || a == "-h"; }

// The same one line as an unknown flag's (tools/cli.cc), with the nearest name when one is close.
int UnknownSubcommand(const SubcommandTable& table, const std::string& name) {
  std::vector<std::string> names;
  for (const Subcommand& s : table.subcommands) names.push_back(s.name);
  const std::string nearest = NearestName(name, names);
  const std::string what = !name.empty() && name[0] == '-' ? "option" : table.kind;
  const std::string suggestion = nearest.empty() ? "" : " (did you mean " + nearest + "?)";
  std::fprintf(stderr, "%s: error: unknown %s '%s'%s; see '%s --help'\n", table.command.c_str(),
               what.c_str(), name.c_str(), suggestion.c_str(), table.command.c_str());
  return 2;
}

}  // namespace

std::string SubcommandUsage(const SubcommandTable& table) {
  std::string text =
      "usage: " + table.command + " <" + table.kind + "> [options]\n\n" + table.kind + "s:\n";
  size_t width = 0;
  for (const Subcommand& s : table.subcommands) width = std::max(width, s.name.size());
  for (const Subcommand& s : table.subcommands) {
    text += "  " + s.name + std::string(width - s.name.size() + 2, ' ');
    for (char c : s.summary)
      text += c == '\n' ? "\n" + std::string(width + 4, ' ') : std::string(1, c);
    text += "\n";
  }
  return text + "\n" + table.footer;
}

const Subcommand* FindSubcommand(const SubcommandTable& table, const std::string& name) {
  for (const Subcommand& s : table.subcommands) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

int RunSubcommand(const SubcommandTable& table, int argc, char** argv) {
  if (argc < 2) {
    std::fputs(SubcommandUsage(table).c_str(), stderr);
    return 2;
  }
  const std::string name = argv[1];
  if (IsHelpFlag(name) || (name == "help" && argc == 2)) {
    std::fputs(SubcommandUsage(table).c_str(), stdout);
    return 0;
  }
  if (name == "help") {
    // `help NAME ARGS...` is `NAME ARGS... --help`: one help text, whichever way it was asked for.
    const Subcommand* s = FindSubcommand(table, argv[2]);
    if (s == nullptr) return UnknownSubcommand(table, argv[2]);
    std::vector<std::string> args(argv + 2, argv + argc);
    args.push_back("--help");
    std::vector<char*> pointers;
    for (std::string& a : args) pointers.push_back(a.data());
    pointers.push_back(nullptr);
    return s->run(int(args.size()), pointers.data());
  }
  const Subcommand* s = FindSubcommand(table, name);
  if (s == nullptr) return UnknownSubcommand(table, name);
  return s->run(argc - 1, argv + 1);
}

}  // namespace tools
}  // namespace ecrf
