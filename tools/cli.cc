#include "tools/cli.h"

#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <thread>

#include "encoder/encode_rate_control.h"

namespace ecrf {
namespace tools {
namespace {

size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// Throws std::invalid_argument with one line: what is wrong, and where help is.
void CheckNoLeftovers(const CLI::App& app) {
  const std::string help = "; see '" + app.get_name() + " --help'";
  for (const std::string& extra : app.remaining()) {
    if (extra.size() > 1 && extra[0] == '-') {
      const std::string flag = extra.substr(0, extra.find('='));
      const std::string near = NearestFlag(app, flag);
      throw std::invalid_argument("unknown option '" + flag + "'" +
                                  (near.empty() ? "" : " (did you mean " + near + "?)") + help);
    }
    throw std::invalid_argument("unexpected argument '" + extra + "'" + help);
  }
}

void Parse(CLI::App* app, std::vector<std::string> args) {
  // CLI11 takes the arguments in reverse order when given as a vector.
  std::reverse(args.begin(), args.end());
  app->parse(args);
}

}  // namespace

std::unique_ptr<CLI::App> MakeCommand(const std::string& name, const std::string& description) {
  auto app = std::make_unique<CLI::App>(description, name);
  app->allow_extras();  // unknown flags are reported by CheckNoLeftovers, with a suggestion
  app->get_formatter()->column_width(34);
  app->get_formatter()->label("REQUIRED", "(required)");
  app->name("ecrf " + name);
  return app;
}

std::string NearestName(const std::string& unknown, const std::vector<std::string>& names) {
  std::string best;
  size_t best_distance = std::max<size_t>(2, unknown.size() / 3) + 1;
  for (const std::string& n : names) {
    const size_t d = EditDistance(unknown, n);
    if (d < best_distance) {
      best_distance = d;
      best = n;
    }
  }
  return best;
}

std::string NearestFlag(const CLI::App& app, const std::string& unknown) {
  std::vector<std::string> names;
  for (const CLI::Option* o : app.get_options()) {
    for (const std::string& l : o->get_lnames()) names.push_back("--" + l);
    for (const std::string& s : o->get_snames()) names.push_back("-" + s);
  }
  return NearestName(unknown, names);
}

bool ParseArguments(CLI::App* app, std::vector<std::string> args) {
  try {
    Parse(app, std::move(args));
  } catch (const CLI::CallForHelp&) {
    std::fputs(app->help().c_str(), stdout);
    return false;
  } catch (const CLI::ParseError& e) {
    // A mistyped flag explains a missing required one ("--elevatio 4 -o x" lacks --elevation's
    // value only because of the typo): name the unknown flag first.
    CheckNoLeftovers(*app);
    throw std::invalid_argument(std::string(e.what()) + "; see '" + app->get_name() + " --help'");
  }
  CheckNoLeftovers(*app);
  return true;
}

int ParseCommandLine(CLI::App* app, int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  try {
    return ParseArguments(app, std::move(args)) ? -1 : 0;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s: error: %s\n", app->get_name().c_str(), e.what());
    return 2;
  }
}

int UsageError(const CLI::App& app, const std::string& message) {
  std::fprintf(stderr, "%s: error: %s; see '%s --help'\n", app.get_name().c_str(), message.c_str(),
               app.get_name().c_str());
  return 2;
}

size_t ParseSizeWithUnit(const std::string& flag, const std::string& text) {
  // The number and units are encoder::ParseByteSize's; the command line adds one rule: a bare
  // number is ambiguous to a reader (bytes or kilobytes?), so it needs a unit.
  char* end = nullptr;
  std::strtod(text.c_str(), &end);
  if (end != text.c_str() && *end == '\0') {
    throw std::invalid_argument(flag + ": '" + text + "' has no unit: write " + text +
                                "B for bytes or " + text +
                                "KB for kilobytes (units: B, KB, MB, KiB, MiB)");
  }
  try {
    return encoder::ParseByteSize(text);
  } catch (const std::invalid_argument&) {
    throw std::invalid_argument(flag + ": '" + text +
                                "': unknown unit or not a size (e.g. 500KB, 1.2MB, 300000B; "
                                "units: B, KB, MB, KiB, MiB)");
  }
}

void AddRenamedFlag(CLI::App* app, const std::string& old_name, const std::string& new_name) {
  app->add_option(old_name)->group("")->each([old_name, new_name](const std::string&) {
    throw CLI::ArgumentMismatch(old_name + " is now called " + new_name);
  });
}

int AllCores() { return std::max(1, omp_get_num_procs()); }

CLI::Option* AddThreadsFlag(CLI::App* app, int* threads) {
  return app
      ->add_option("--threads", *threads,
                   "worker threads (0 = all cores: " + std::to_string(AllCores()) + ")")
      ->type_name("N")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
}

void ApplyThreads(int threads) { omp_set_num_threads(threads > 0 ? threads : AllCores()); }

}  // namespace tools
}  // namespace ecrf
