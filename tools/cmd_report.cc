// `ecrf report`: rate–distortion sweeps, the renderer's speed against its error, BD-rate.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "tools/cli_args.h"
#include "tools/commands.h"
#include "tools/report.h"

namespace ecrf {
namespace tools {
namespace {

const char kReportUsage[] =
    "usage: ecrf report <what> [options]\n"
    "  sweep    train one run per lambda_e, encode, decode, score: the rate-distortion report\n"
    "           ecrf report sweep --data DIR --lambdas 0,2e-11,1e-10,5e-10 -o REPORT [--render]\n"
    "  render   the speed-error sweep of the renderer on one rate point: ecrf report render REPORT\n"
    "  compare  BD-rate and BD-PSNR of B against A: ecrf report compare A B [--json FILE] [--plot FILE.png]\n"
    "  plot     redraw the plots and index.html from REPORT/report.json: ecrf report plot REPORT\n"
    "`ecrf report <what> --help` for the options of each.\n";

const char kCompareUsage[] =
    "usage: ecrf report compare A B [--json FILE] [--plot FILE.png]\n"
    "  A, B            report directories or their report.json; A is the anchor\n"
    "  --json FILE     write the result as JSON\n"
    "  --plot FILE.png draw both curves (writes FILE.csv beside it)\n";

int RunReportPlot(int argc, char** argv) {
  if (argc != 2 || argv[1][0] == '-') {
    const bool help = argc == 2 && (!std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h"));
    std::fputs("usage: ecrf report plot REPORT_DIR\n", help ? stdout : stderr);
    return help ? 0 : 2;
  }
  return WriteReport(argv[1], ReadReport(argv[1])) ? 0 : 1;
}

}  // namespace

int RunReportCompare(int argc, char** argv) {
  std::string paths[2], json_path, plot_path;
  int given = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::fputs(kCompareUsage, stdout);
      return 0;
    } else if (a == "--json") {
      json_path = FlagValue(argc, argv, &i);
    } else if (a == "--plot") {
      plot_path = FlagValue(argc, argv, &i);
    } else if (a[0] != '-' && given < 2) {
      paths[given++] = a;
    } else {
      std::fprintf(stderr, "ecrf report compare: unexpected argument '%s'\n\n%s", a.c_str(), kCompareUsage);
      return 2;
    }
  }
  if (given != 2) {
    std::fprintf(stderr, "ecrf report compare: needs two reports\n\n%s", kCompareUsage);
    return 2;
  }
  const nlohmann::json a = ReadReport(paths[0]), b = ReadReport(paths[1]);
  const BdResult r = Bjontegaard(RateDistortionCurve(a), RateDistortionCurve(b));
  if (!r.ok) throw std::runtime_error("cannot compare " + paths[0] + " and " + paths[1] + ": " + r.error);
  std::printf("B = %s against A = %s (decoded-file PSNR vs file bytes, PCHIP):\n", paths[1].c_str(), paths[0].c_str());
  std::printf("  BD-rate %+.2f%%  (B needs %.2f%% %s bytes than A for the same PSNR, over %.2f-%.2f dB)\n", r.bd_rate,
              std::fabs(r.bd_rate), r.bd_rate <= 0 ? "fewer" : "more", r.psnr_range[0], r.psnr_range[1]);
  std::printf("  BD-PSNR %+.3f dB  (at the same size, over %.0f-%.0f bytes)\n", r.bd_psnr, r.rate_range[0],
              r.rate_range[1]);
  if (!json_path.empty()) {
    const nlohmann::json j = {{"anchor", paths[0]},
                              {"test", paths[1]},
                              {"bd_rate_percent", r.bd_rate},
                              {"bd_psnr_db", r.bd_psnr},
                              {"psnr_range_db", {r.psnr_range[0], r.psnr_range[1]}},
                              {"rate_range_bytes", {r.rate_range[0], r.rate_range[1]}},
                              {"interpolation", "pchip"},
                              {"distortion", "decoded-file test PSNR"},
                              {"rate", "file bytes"}};
    WriteTextFile(json_path, j.dump(2) + "\n");
  }
  if (!plot_path.empty()) {
    const std::string csv = CompareCsv({{"A: " + paths[0], RateDistortionCurve(a)},
                                        {"B: " + paths[1], RateDistortionCurve(b)}});
    const std::string csv_path = plot_path.substr(0, plot_path.rfind('.')) + ".csv";
    WriteTextFile(csv_path, csv);
    if (!DrawComparePlot(plot_path, csv_path)) return 1;
  }
  return 0;
}

int RunReport(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    std::fputs(kReportUsage, argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const std::string what = argv[1];
  if (what == "sweep") return RunReportSweep(argc - 1, argv + 1);
  if (what == "render") return RunReportRender(argc - 1, argv + 1);
  if (what == "compare") return RunReportCompare(argc - 1, argv + 1);
  if (what == "plot") return RunReportPlot(argc - 1, argv + 1);
  std::fprintf(stderr, "ecrf report: unknown report '%s'\n\n%s", what.c_str(), kReportUsage);
  return 2;
}

}  // namespace tools
}  // namespace ecrf
