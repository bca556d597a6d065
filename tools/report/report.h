// `ecrf report`: rate–distortion and speed–error reports of ecrf on a scene.
//
// A report is a directory: report.json (everything measured; the source of every other file),
// one CSV per plot, PNG plots drawn by tools/report/plot_report.py when matplotlib is there,
// index.html (tables, and the plots that exist), and runs/ with one training run per rate point.
#ifndef ECRF_TOOLS_REPORT_REPORT_H_
#define ECRF_TOOLS_REPORT_REPORT_H_

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "tools/report/bd_rate.h"

namespace ecrf {
namespace tools {

int RunReport(int argc, char** argv);

// Subcommands (argv[0] is the subcommand's name).
int RunReportSweep(int argc, char** argv);
int RunReportRender(int argc, char** argv);
int RunReportCompare(int argc, char** argv);

// "lambda_1e-10" for 1e-10, "lambda_2e-11_steps3" for 2e-11 with steps x3: the run directory's
// name of a rate point.
std::string LambdaText(double lambda, double step_scale = 1.0);

// One rate point from a finished run's metrics.json (file size, decoded and float PSNR/SSIM,
// bytes per chunk, training curve), and the derived columns against the lambda = 0 reference
// once all points are known.
nlohmann::json RatePointFromMetrics(const nlohmann::json& metrics, const std::string& run_dir);
void AddReferenceColumns(nlohmann::json* report);

// The decoded-file curve of a report: (file bytes, decoded PSNR) per point.
std::vector<RdPoint> RateDistortionCurve(const nlohmann::json& report);

// The lambda = 0 float32 reference of the earlier sweep in dir, for a sweep (report["sweep"]) of
// data without one: same data, preset, seed, test views and downscale; the same iterations, or the
// preset's own schedule (the `fast` reference stays the yardstick of a longer-trained sweep).
// Throws saying which setting differs.
nlohmann::json BorrowReference(const std::string& dir, const nlohmann::json& sweep,
                               const std::string& data);

// The anchors of an --anchors file (docs/reports/anchors_*.json) drawn on `scene`'s report: those
// without a "scene" (dataset averages, relative figures) and those of that scene
// (case-insensitive). Each needs a label and file_bytes and psnr, or ratio and psnr_loss_db; throws
// naming the entry. An empty path gives none.
nlohmann::json ReadAnchors(const std::string& path, const std::string& scene);

// Parses a JSON file (throws naming the file).
nlohmann::json ReadJsonFile(const std::string& path);

// Reads REPORT/report.json (throws naming the file when it is missing or not a report).
nlohmann::json ReadReport(const std::string& dir);

// Writes report.json, the CSVs, the plots (when it can) and index.html into dir, each file
// atomically. Returns false when the plots could not be drawn (and says why on stderr).
bool WriteReport(const std::string& dir, const nlohmann::json& report);

// compare.csv: series,file_bytes,psnr,left_out,work_per_pixel,seconds_per_view for the points of
// each named report (left_out 1: a point its own curve beats, outside the Pareto front that
// BD-rate integrates; the last two: what a view of the point's file costs, empty when unknown).
std::string CompareCsv(const std::vector<std::pair<std::string, nlohmann::json>>& reports);

// Draws compare.csv into png; false when it could not.
bool DrawComparePlot(const std::string& png, const std::string& csv);

// Writes `text` to path through a temporary file and a rename.
void WriteTextFile(const std::string& path, const std::string& text);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_REPORT_REPORT_H_
