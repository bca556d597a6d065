// `ecrf report`: rate–distortion sweeps, the renderer's speed against its error, BD-rate.
#include <cmath>
#include <cstdio>
#include <stdexcept>
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

int RunReportCompare(int argc, char** argv) {
  std::string paths[2], json_path, plot_path;
  auto app = MakeCommand(
      "report compare",
      "BD-rate and BD-PSNR of report B against report A (decoded-file PSNR against file bytes, "
      "PCHIP interpolation)");
  app->add_option("A", paths[0], "the anchor: a report directory or its report.json")
      ->type_name("REPORT")
      ->required();
  app->add_option("B", paths[1], "the report compared with A")->type_name("REPORT")->required();
  app->add_option("--json", json_path, "write the result as JSON")->type_name("FILE");
  app->add_option("--plot", plot_path, "draw both curves (writes FILE.csv beside it)")
      ->type_name("FILE.png");
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  const nlohmann::json a = ReadReport(paths[0]), b = ReadReport(paths[1]);
  const BdResult r = Bjontegaard(RateDistortionCurve(a), RateDistortionCurve(b));
  if (!r.ok)
    throw std::runtime_error("cannot compare " + paths[0] + " and " + paths[1] + ": " + r.error);
  std::printf("B = %s against A = %s (decoded-file PSNR vs file bytes, PCHIP):\n", paths[1].c_str(),
              paths[0].c_str());
  auto bound = [](int b) { return b > 0 ? "at most " : b < 0 ? "at least " : ""; };
  if (r.bd_rate_bound == 0) {
    std::printf(
        "  BD-rate %+.2f%%  (B needs %.2f%% %s bytes than A for the same PSNR, over %.2f-%.2f "
        "dB)\n",
        r.bd_rate, std::fabs(r.bd_rate), r.bd_rate <= 0 ? "fewer" : "more", r.psnr_range[0],
        r.psnr_range[1]);
  } else {
    std::printf(
        "  BD-rate %s%+.2f%%  (the PSNRs do not overlap: B is %s A's %.2f-%.2f dB at every size; "
        "the bound holds B at its %s file)\n",
        bound(r.bd_rate_bound), r.bd_rate, r.bd_rate_bound > 0 ? "above" : "below", r.psnr_range[0],
        r.psnr_range[1], r.bd_rate_bound > 0 ? "smallest" : "largest");
  }
  if (r.bd_psnr_bound == 0) {
    std::printf("  BD-PSNR %+.3f dB  (at the same size, over %.0f-%.0f bytes)\n", r.bd_psnr,
                r.rate_range[0], r.rate_range[1]);
  } else {
    std::printf(
        "  BD-PSNR %s%+.3f dB  (the sizes do not overlap: B's files are all %s A's %.0f-%.0f "
        "bytes; the bound holds B at its %s file)\n",
        bound(r.bd_psnr_bound), r.bd_psnr, r.bd_psnr_bound < 0 ? "below" : "above", r.rate_range[0],
        r.rate_range[1], r.bd_psnr_bound < 0 ? "largest" : "smallest");
  }
  nlohmann::json left_out[2];
  for (int c = 0; c < 2; ++c) {
    left_out[c] = nlohmann::json::array();
    for (const RdPoint& p : r.dominated[c]) {
      std::printf("  left out of %s: %.0f bytes at %.2f dB (a point of its own curve is better)\n",
                  c == 0 ? "A" : "B", p.rate, p.psnr);
      left_out[c].push_back({{"file_bytes", p.rate}, {"decoded_psnr", p.psnr}});
    }
  }
  if (!json_path.empty()) {
    auto bound_name = [](int b) { return b > 0 ? "upper bound" : b < 0 ? "lower bound" : "value"; };
    const nlohmann::json j = {{"anchor", paths[0]},
                              {"test", paths[1]},
                              {"bd_rate_percent", r.bd_rate},
                              {"bd_psnr_db", r.bd_psnr},
                              {"bd_rate_is", bound_name(r.bd_rate_bound)},
                              {"bd_psnr_is", bound_name(r.bd_psnr_bound)},
                              {"psnr_range_db", {r.psnr_range[0], r.psnr_range[1]}},
                              {"rate_range_bytes", {r.rate_range[0], r.rate_range[1]}},
                              {"anchor_points_left_out", left_out[0]},
                              {"test_points_left_out", left_out[1]},
                              {"interpolation", "pchip"},
                              {"distortion", "decoded-file test PSNR"},
                              {"rate", "file bytes"}};
    WriteTextFile(json_path, j.dump(2) + "\n");
  }
  if (!plot_path.empty()) {
    const std::string csv = CompareCsv({{"A: " + paths[0], a}, {"B: " + paths[1], b}});
    const std::string csv_path = plot_path.substr(0, plot_path.rfind('.')) + ".csv";
    WriteTextFile(csv_path, csv);
    if (!DrawComparePlot(plot_path, csv_path)) return 1;
  }
  return 0;
}

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
           "BD-rate and BD-PSNR of B against A: ecrf report compare A B [--json FILE] [--plot "
           "FILE.png]"},
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
