// The ecrf subcommands (one file each). argv[0] is the subcommand name; each returns an exit code.
#ifndef ECRF_TOOLS_COMMANDS_H_
#define ECRF_TOOLS_COMMANDS_H_

namespace ecrf {
namespace tools {

// The whole command line (argv[0] is the program): dispatch, `ecrf help`, --version, and
// exceptions turned into "ecrf CMD: error: ..." with exit code 1. main() is this.
int RunEcrf(int argc, char** argv);

int RunSelfCheck(int argc, char** argv);
int RunTrain(int argc, char** argv);
int RunConformance(int argc, char** argv);
int RunEncode(int argc, char** argv);
int RunInfo(int argc, char** argv);
int RunRender(int argc, char** argv);
int RunEval(int argc, char** argv);
int RunReport(int argc, char** argv);
int RunPrepare(int argc, char** argv);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_COMMANDS_H_
