// The ecrf command-line tool: one binary, one subcommand per job (tools/ecrf_command.cc; the
// commands live in the ecrf_tools library so that the tests can run them in-process).
#include "tools/commands.h"

int main(int argc, char** argv) { return ecrf::tools::RunEcrf(argc, argv); }
