// `ecrf report compare`: Bjontegaard deltas of reports against an anchor, and their curves drawn
// together (one rate-distortion curve per head is a compare of sweeps that differ in --head).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "tools/cli.h"
#include "tools/report/report.h"

namespace ecrf {
namespace tools {
namespace {

const char* BoundWord(int bound) { return bound > 0 ? "at most " : bound < 0 ? "at least " : ""; }
const char* BoundName(int bound) {
  return bound > 0 ? "upper bound" : bound < 0 ? "lower bound" : "value";
}

nlohmann::json PointsJson(const std::vector<RdPoint>& points) {
  nlohmann::json out = nlohmann::json::array();
  for (const RdPoint& p : points) out.push_back({{"file_bytes", p.rate}, {"decoded_psnr", p.psnr}});
  return out;
}

void PrintResult(const BdResult& r, const std::string& test, const std::string& anchor) {
  std::printf("%s against %s (decoded-file PSNR vs file bytes, PCHIP):\n", test.c_str(),
              anchor.c_str());
  if (r.bd_rate_bound == 0) {
    std::printf(
        "  BD-rate %+.2f%%  (%s needs %.2f%% %s bytes for the same PSNR, over %.2f-%.2f dB)\n",
        r.bd_rate, test.c_str(), std::fabs(r.bd_rate), r.bd_rate <= 0 ? "fewer" : "more",
        r.psnr_range[0], r.psnr_range[1]);
  } else {
    std::printf(
        "  BD-rate %s%+.2f%%  (the PSNRs do not overlap: %s is %s %.2f-%.2f dB at every size; the "
        "bound holds it at its %s file)\n",
        BoundWord(r.bd_rate_bound), r.bd_rate, test.c_str(),
        r.bd_rate_bound > 0 ? "above" : "below", r.psnr_range[0], r.psnr_range[1],
        r.bd_rate_bound > 0 ? "smallest" : "largest");
  }
  if (r.bd_psnr_bound == 0) {
    std::printf("  BD-PSNR %+.3f dB  (at the same size, over %.0f-%.0f bytes)\n", r.bd_psnr,
                r.rate_range[0], r.rate_range[1]);
  } else {
    std::printf(
        "  BD-PSNR %s%+.3f dB  (the sizes do not overlap: its files are all %s %.0f-%.0f bytes; "
        "the bound holds it at its %s file)\n",
        BoundWord(r.bd_psnr_bound), r.bd_psnr, r.bd_psnr_bound < 0 ? "below" : "above",
        r.rate_range[0], r.rate_range[1], r.bd_psnr_bound < 0 ? "largest" : "smallest");
  }
  for (const RdPoint& p : r.dominated[1]) {
    std::printf("  left out of %s: %.0f bytes at %.2f dB (a point of its own curve is better)\n",
                test.c_str(), p.rate, p.psnr);
  }
}

}  // namespace

int RunReportCompare(int argc, char** argv) {
  std::vector<std::string> paths, labels;
  std::string json_path, plot_path;
  auto app = MakeCommand(
      "report compare",
      "BD-rate and BD-PSNR of each report against the first (decoded-file PSNR against file "
      "bytes, PCHIP interpolation); --plot draws every curve");
  app->add_option("REPORTS", paths,
                  "the anchor A, then the reports compared with it (B, C, ...): report "
                  "directories or their report.json")
      ->expected(2, 64)
      ->required();
  app->add_option("--label", labels,
                  "the name of a curve, once per report in the order of REPORTS (default: A, B, "
                  "... and the path)")
      ->allow_extra_args(false)
      ->type_name("NAME");
  app->add_option("--json", json_path, "write the result as JSON")->type_name("FILE");
  app->add_option("--plot", plot_path, "draw the curves (writes FILE.csv beside it)")
      ->type_name("FILE.png");
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  if (!labels.empty() && labels.size() != paths.size()) {
    throw std::runtime_error("--label names " + std::to_string(labels.size()) + " curves for " +
                             std::to_string(paths.size()) + " reports");
  }
  // The outputs' folders first: a mistyped path fails before any work, not after it.
  for (const std::string& out : {json_path, plot_path}) {
    const std::filesystem::path parent = std::filesystem::path(out).parent_path();
    if (!out.empty() && !parent.empty()) std::filesystem::create_directories(parent);
  }
  std::vector<std::pair<std::string, nlohmann::json>> reports;
  for (size_t i = 0; i < paths.size(); ++i) {
    const std::string letter(1, char('A' + i));
    reports.emplace_back(labels.empty() ? letter + ": " + paths[i] : labels[i],
                         ReadReport(paths[i]));
  }
  const std::vector<RdPoint> anchor = RateDistortionCurve(reports[0].second);
  nlohmann::json comparisons = nlohmann::json::array();
  std::vector<RdPoint> anchor_left_out;  // the same for every comparison
  bool compared = false;
  std::string not_compared;
  for (size_t i = 1; i < reports.size(); ++i) {
    const BdResult r = Bjontegaard(anchor, RateDistortionCurve(reports[i].second));
    if (!r.ok) {  // drawn all the same (a single point is a cost point worth seeing)
      const std::string why = "cannot compare " + paths[i] + " with " + paths[0] + ": " + r.error;
      std::printf("%s: not compared (%s)\n", reports[i].first.c_str(), r.error.c_str());
      comparisons.push_back({{"test", paths[i]}, {"label", reports[i].first}, {"error", r.error}});
      if (not_compared.empty()) not_compared = why;
      continue;
    }
    PrintResult(r, reports[i].first, reports[0].first);
    anchor_left_out = r.dominated[0];
    compared = true;
    comparisons.push_back({{"test", paths[i]},
                           {"label", reports[i].first},
                           {"bd_rate_percent", r.bd_rate},
                           {"bd_psnr_db", r.bd_psnr},
                           {"bd_rate_is", BoundName(r.bd_rate_bound)},
                           {"bd_psnr_is", BoundName(r.bd_psnr_bound)},
                           {"psnr_range_db", {r.psnr_range[0], r.psnr_range[1]}},
                           {"rate_range_bytes", {r.rate_range[0], r.rate_range[1]}},
                           {"test_points_left_out", PointsJson(r.dominated[1])}});
  }
  for (const RdPoint& p : anchor_left_out) {
    std::printf("left out of %s: %.0f bytes at %.2f dB (a point of its own curve is better)\n",
                reports[0].first.c_str(), p.rate, p.psnr);
  }
  if (!json_path.empty()) {
    const nlohmann::json j = {{"anchor", paths[0]},
                              {"anchor_label", reports[0].first},
                              {"anchor_points_left_out", PointsJson(anchor_left_out)},
                              {"comparisons", comparisons},
                              {"interpolation", "pchip"},
                              {"distortion", "decoded-file test PSNR"},
                              {"rate", "file bytes"}};
    WriteTextFile(json_path, j.dump(2) + "\n");
  }
  if (!plot_path.empty()) {
    const std::string csv_path = plot_path.substr(0, plot_path.rfind('.')) + ".csv";
    WriteTextFile(csv_path, CompareCsv(reports));
    if (!DrawComparePlot(plot_path, csv_path)) return 1;
  }
  // The curves are drawn and listed all the same; that none could be compared is still an error.
  if (!compared) throw std::runtime_error(not_compared);
  return 0;
}

}  // namespace tools
}  // namespace ecrf
