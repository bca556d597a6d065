// `ecrf report`: rate–distortion sweeps, the renderer's speed against its error, BD-rate.
#include <string>

#include "tools/cli.h"
#include "tools/commands.h"
#include "tools/report/component_drop.h"
#include "tools/report/quant_sensitivity.h"
#include "tools/report/report.h"
#include "tools/subcommands.h"

namespace ecrf {
namespace tools {
namespace {

int RunReportPlot(int argc, char** argv) {
  std::string dir;
  auto app = MakeCommand("report plot",
                         "redraw the plots and index.html of a report from its report.json");
  app->add_option("REPORT", dir, "the report directory")->type_name("DIR")->required();
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  return WriteReport(dir, ReadReport(dir)) ? 0 : 1;
}

}  // namespace

int RunReport(int argc, char** argv) {
  static const SubcommandTable table = {
      "ecrf report",
      "report",
      {
          {"sweep", RunReportSweep,
           "train one run per lambda_e, encode, decode, score: the rate-distortion report\n"
           "ecrf report sweep --data DIR --lambdas 0,2e-11,1e-10,5e-10 -o REPORT [--render]"},
          {"render", RunReportRender,
           "the speed-error sweep of the renderer on one rate point: ecrf report render REPORT"},
          {"compare", RunReportCompare,
           "BD-rate and BD-PSNR of each report against the first, one curve each: ecrf report "
           "compare A B [C ...] [--label NAME ...] [--json FILE] [--plot FILE.png]"},
          {"sensitivity", RunReportSensitivity,
           "where quantization costs PSNR, tensor by tensor: ecrf report sensitivity RUN"},
          {"components", RunReportComponents,
           "which components are worth their bits, a drop test each: ecrf report components RUN"},
          {"plot", RunReportPlot,
           "redraw the plots and index.html from REPORT/report.json: ecrf report plot REPORT"},
      },
      "`ecrf report <report> --help` (or `ecrf help report <report>`) for the options of each.\n"};
  return RunSubcommand(table, argc, argv);
}

}  // namespace tools
}  // namespace ecrf
