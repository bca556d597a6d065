// `ecrf report` end to end on the built-in scene: a two-point sweep with the speed-error sweep,
// checked against `ecrf eval` on the same files, resumed, refused when incompatible, compared.
#include <gtest/gtest.h>
#include <unistd.h>
#include <filesystem>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/common/invoke.h"
#include "tests/common/scoped_temp_dir.h"
#include "tools/commands.h"
#include "tools/report/report.h"

namespace ecrf {
namespace tools {
namespace {

using testing_cli::Invoke;

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

nlohmann::json ReadJson(const std::string& path) { return nlohmann::json::parse(ReadText(path)); }

std::vector<std::vector<std::string>> ReadCsv(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.push_back("");
    rows.push_back(cells);
  }
  return rows;
}

// One sweep (two trainings) serves every check: ctest runs each TEST in its own process.
std::string root_, dir_;

void WritesEveryFile() {
  for (const char* f :
       {"report.json", "rd.csv", "chunks.csv", "curve.csv", "speed.csv", "index.html",
        "runs/lambda_0/scene.ecrf", "runs/lambda_1e-08_steps2/scene.ecrf"}) {
    EXPECT_FALSE(ReadText(dir_ + "/" + f).empty()) << f;
  }
  const std::string html = ReadText(dir_ + "/index.html");
  EXPECT_NE(html.find("lambda=1e-08"), std::string::npos);
  EXPECT_NE(html.find("Speed against error"), std::string::npos);
  // Published tables need the views and their size said: the built-in scene's 64x64 test views.
  EXPECT_NE(html.find("over 4 test views of 64x64"), std::string::npos);
  EXPECT_EQ(ReadJson(dir_ + "/report.json")["points"][0]["test_image_size"],
            nlohmann::json::array({64, 64}));
  EXPECT_NE(html.find("</html>"), std::string::npos);
}

void RatePointsAreWhatEvalMeasuresOnTheSameFiles() {
  const nlohmann::json r = ReadJson(dir_ + "/report.json");
  ASSERT_EQ(r["points"].size(), 2u);
  const auto rd = ReadCsv(dir_ + "/rd.csv");
  ASSERT_EQ(rd.size(), 3u);
  ASSERT_EQ(rd[0][2], "file_bytes");
  ASSERT_EQ(rd[0][3], "decoded_psnr");
  for (size_t k = 0; k < 2; ++k) {
    const nlohmann::json& p = r["points"][k];
    const std::string file = dir_ + "/" + p["run_dir"].get<std::string>() + "/scene.ecrf";
    const std::string json = root_ + "/eval.json";
    ASSERT_EQ(Invoke(RunEval, {"eval", file, "--scene", "builtin", "--seed", "7",
                               "--max-test-views", "4", "--threads", "2", "--json", json}),
              0);
    const nlohmann::json e = ReadJson(json);
    EXPECT_EQ(e["bytes"], p["file_bytes"]);
    EXPECT_DOUBLE_EQ(e["psnr"].get<double>(), p["decoded_psnr"].get<double>());
    EXPECT_DOUBLE_EQ(e["ssim"].get<double>(), p["decoded_ssim"].get<double>());
    EXPECT_EQ(e["views"], 4);
    // The CSV row says the same as report.json.
    EXPECT_EQ(std::stod(rd[k + 1][2]), p["file_bytes"].get<double>());
    EXPECT_NEAR(std::stod(rd[k + 1][3]), p["decoded_psnr"].get<double>(), 1e-8);
    // What a view of the file costs (#57): the decoder's count, whatever the threads.
    EXPECT_EQ(p["head"], e["head"]);
    EXPECT_EQ(p["head"], "mlp");
    EXPECT_GT(p["decoded_work_per_pixel"].get<double>(), 0.0);
    EXPECT_DOUBLE_EQ(e["work_per_pixel"].get<double>(), p["decoded_work_per_pixel"].get<double>());
    ASSERT_EQ(rd[0][12], "head");
    ASSERT_EQ(rd[0][14], "work_per_pixel");
    EXPECT_EQ(rd[k + 1][12], "mlp");
    EXPECT_NEAR(std::stod(rd[k + 1][14]), p["decoded_work_per_pixel"].get<double>(), 1e-3);
    // The chunk breakdown adds up to the file.
    double sum = 0;
    for (const auto& [name, bytes] : p["chunks"].items()) sum += bytes.get<double>();
    EXPECT_EQ(sum, p["file_bytes"].get<double>());
    // Against the lambda = 0 float32 model.
    const nlohmann::json& ref = r["reference"];
    EXPECT_DOUBLE_EQ(p["ratio"].get<double>(),
                     ref["float32_bytes"].get<double>() / p["file_bytes"].get<double>());
    EXPECT_DOUBLE_EQ(p["psnr_loss_db"].get<double>(),
                     p["decoded_psnr"].get<double>() - ref["float_psnr"].get<double>());
    EXPECT_FALSE(p["curve"].empty());
  }
  EXPECT_EQ(ReadCsv(dir_ + "/chunks.csv").size(), 1 + 2 * r["points"][0]["chunks"].size());
}

void SpeedRowsObeyWhatTheSpecPromises() {
  const nlohmann::json r = ReadJson(dir_ + "/report.json");
  const nlohmann::json& speed = r["speed"];
  ASSERT_TRUE(speed.is_object());
  // The middle point of a two-point sweep is the second.
  EXPECT_EQ(speed["point"], "lambda=1e-08 steps x2");
  const double default_psnr = r["points"][1]["decoded_psnr"].get<double>();
  auto row = [&](const std::string& knob, const std::string& setting) {
    for (const nlohmann::json& x : speed["rows"]) {
      if (x["knob"] == knob && x["setting"] == setting) return x;
    }
    ADD_FAILURE() << "no row " << knob << " " << setting;
    return nlohmann::json();
  };
  // Same views and options as the rate point: the same PSNR to the bit.
  EXPECT_DOUBLE_EQ(row("default", "default")["psnr"].get<double>(), default_psnr);
  // Thread count and empty-space skipping never change a pixel (SPEC.md 7.8).
  EXPECT_DOUBLE_EQ(row("threads", "1")["psnr"].get<double>(), default_psnr);
  EXPECT_DOUBLE_EQ(row("skip_empty_space", "off")["psnr"].get<double>(), default_psnr);
  // Early termination at 1e-4 moves a channel by less than 1e-4: PSNR within 0.01 dB of the
  // reference.
  EXPECT_NEAR(row("early_stop", "0")["psnr"].get<double>(), default_psnr, 0.01);
  EXPECT_GE(row("early_stop", "0")["samples_per_ray"].get<double>(),
            row("default", "default")["samples_per_ray"].get<double>());
  // Half the samples per ray.
  EXPECT_NEAR(row("step_scale", "2")["samples_per_ray"].get<double>(),
              row("default", "default")["samples_per_ray"].get<double>() / 2,
              0.15 * row("default", "default")["samples_per_ray"].get<double>());
  // A higher weight threshold runs the MLP less often.
  EXPECT_LT(row("weight_threshold", "0.01")["mlp_samples_per_ray"].get<double>(),
            row("default", "default")["mlp_samples_per_ray"].get<double>());
  EXPECT_EQ(row("image_scale", "1/2")["width"], 32);
  EXPECT_GT(speed["decode"]["float32_grid_bytes"].get<double>(),
            speed["decode"]["int16_grid_bytes"].get<double>());
  EXPECT_EQ(ReadCsv(dir_ + "/speed.csv").size(), 1 + speed["rows"].size());
}

void SweepResumesFromFinishedRunsAndRefusesIncompatibleOnes() {
  const nlohmann::json before = ReadJson(dir_ + "/report.json");
  // Same sweep again: nothing is trained (the runs' metrics are reused), the points are the same.
  ASSERT_EQ(Invoke(RunReport, {"report", "sweep", "--scene", "builtin", "--lambdas", "0,1e-8@2",
                               "--iters", "120", "--batch", "512", "--final-grid", "48",
                               "--max-test-views", "4", "--seed", "7", "-o", dir_}),
            0);
  const nlohmann::json after = ReadJson(dir_ + "/report.json");
  EXPECT_EQ(after["points"], before["points"]);
  // A point's own step scale names its run and labels it.
  ASSERT_EQ(after["points"].size(), 2u);
  EXPECT_EQ(after["points"][1]["run_dir"], "runs/lambda_1e-08_steps2");
  EXPECT_EQ(after["points"][1]["label"], "lambda=1e-08 steps x2");
  EXPECT_EQ(after["points"][1]["quant_step_scale"], 2.0);
  EXPECT_EQ(after["points"][0]["quant_step_scale"], 1.0);
  EXPECT_TRUE(after.contains("speed"));
  // Other iterations: the finished runs no longer match, and the sweep says so.
  try {
    Invoke(RunReport,
           {"report", "sweep", "--scene", "builtin", "--lambdas", "0", "--iters", "121", "--batch",
            "512", "--final-grid", "48", "--max-test-views", "4", "--seed", "7", "-o", dir_});
    ADD_FAILURE() << "an incompatible finished run was reused";
  } catch (const std::exception& e) {
    // The run's config.json against the sweep's settings, named as config.json names them.
    EXPECT_NE(std::string(e.what()).find("iters: 120 -> 121"), std::string::npos) << e.what();
  }
}

void CompareAgainstItselfIsZero() {
  const std::string json = root_ + "/compare.json";
  ASSERT_EQ(Invoke(RunReport, {"report", "compare", dir_, dir_ + "/report.json", "--json", json}),
            0);
  const nlohmann::json c = ReadJson(json);
  ASSERT_EQ(c["comparisons"].size(), 1u);
  EXPECT_NEAR(c["comparisons"][0]["bd_rate_percent"].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(c["comparisons"][0]["bd_psnr_db"].get<double>(), 0.0, 1e-9);
  // Three curves (as one per head): each compared with the first, each drawn under its label.
  // (exit 1 only when matplotlib cannot draw: the JSON and CSV are written first)
  Invoke(RunReport, {"report", "compare", dir_, dir_, dir_, "--label", "mlp", "--label", "deferred",
                     "--label", "sh", "--json", json, "--plot", root_ + "/heads.png"});
  const nlohmann::json three = ReadJson(json);
  ASSERT_EQ(three["comparisons"].size(), 2u);
  EXPECT_EQ(three["anchor_label"], "mlp");
  EXPECT_EQ(three["comparisons"][1]["label"], "sh");
  EXPECT_NEAR(three["comparisons"][1]["bd_psnr_db"].get<double>(), 0.0, 1e-9);
  const auto heads = ReadCsv(root_ + "/heads.csv");
  ASSERT_EQ(heads.size(), 7u);  // header, two points per series
  EXPECT_EQ(heads[1][0], "mlp");
  EXPECT_EQ(heads[3][0], "deferred");
  EXPECT_EQ(heads[5][0], "sh");
  // A one-point report (one file of a head) cannot be integrated, but is drawn and listed.
  nlohmann::json one = ReadJson(dir_ + "/report.json");
  one["points"].erase(1);
  std::filesystem::create_directories(root_ + "/one");
  WriteTextFile(root_ + "/one/report.json", one.dump());
  Invoke(RunReport, {"report", "compare", dir_, dir_, root_ + "/one", "--json", json, "--plot",
                     root_ + "/one.png"});
  const nlohmann::json partial = ReadJson(json);
  ASSERT_EQ(partial["comparisons"].size(), 2u);
  EXPECT_FALSE(partial["comparisons"][0].contains("error"));
  EXPECT_NE(partial["comparisons"][1]["error"].get<std::string>().find("two points"),
            std::string::npos);
  EXPECT_EQ(ReadCsv(root_ + "/one.csv").size(), 6u);  // header, 2 + 2 + 1 points
  EXPECT_THROW(Invoke(RunReport, {"report", "compare", dir_, root_ + "/one"}), std::runtime_error);
  EXPECT_THROW(Invoke(RunReport, {"report", "compare", dir_, dir_, "--label", "a"}),
               std::runtime_error);
  // --plot: the points' table (written with or without matplotlib) carries each file's cost.
  const int drawn =
      Invoke(RunReport, {"report", "compare", dir_, dir_, "--plot", root_ + "/compare.png"});
  const auto rows = ReadCsv(root_ + "/compare.csv");
  ASSERT_EQ(rows.size(), 5u);  // header, two points per series
  ASSERT_EQ(rows[0][4], "work_per_pixel");
  ASSERT_EQ(rows[0][5], "seconds_per_view");
  for (size_t k = 1; k < rows.size(); ++k) {
    EXPECT_GT(std::stod(rows[k][4]), 0.0);
    EXPECT_GT(std::stod(rows[k][5]), 0.0);
  }
  if (drawn == 0) EXPECT_FALSE(ReadText(root_ + "/compare_cost.png").empty());
}

// A point names its file's head as metrics.json does, and a head without an MLP (hidden 0) sh,
// as runs from before the sh head had its own name did not.
void PointsNameTheirHead() {
  nlohmann::json m = ReadJson(dir_ + "/runs/lambda_0/metrics.json");
  EXPECT_EQ(RatePointFromMetrics(m, "r")["head"], "mlp");
  m["head"] = "deferred";
  EXPECT_EQ(RatePointFromMetrics(m, "r")["head"], "deferred");
  m["mlp_hidden"] = 0;
  EXPECT_EQ(RatePointFromMetrics(m, "r")["head"], "sh");
  m.erase("head");
  m.erase("mlp_hidden");
  EXPECT_EQ(RatePointFromMetrics(m, "r")["head"], "mlp");  // before #57: the per-sample head
}

TEST(Report, BuiltinSweepMatchesEvalResumesAndCompares) {
  const testing_util::ScopedTempDir tmp("ecrf_report_test");
  root_ = tmp.path();
  dir_ = root_ + "/nested/report";  // parents do not exist yet
  // Plots are drawn when matplotlib is installed; the checks below read the tables either way.
  ASSERT_EQ(Invoke(RunReport, {"report",           "sweep",    "--scene",      "builtin",
                               "--lambdas",        "0,1e-8@2", "--iters",      "120",
                               "--batch",          "512",      "--final-grid", "48",
                               "--max-test-views", "4",        "--seed",       "7",
                               "--threads",        "2",        "-o",           dir_}),
            0);
  ASSERT_EQ(Invoke(RunReport, {"report", "render", dir_, "--test-stride", "1"}), 0);
  {
    SCOPED_TRACE("files");
    WritesEveryFile();
  }
  {
    SCOPED_TRACE("rate points vs ecrf eval");
    RatePointsAreWhatEvalMeasuresOnTheSameFiles();
  }
  {
    SCOPED_TRACE("speed rows");
    SpeedRowsObeyWhatTheSpecPromises();
  }
  {
    SCOPED_TRACE("compare");
    CompareAgainstItselfIsZero();
  }
  {
    SCOPED_TRACE("heads");
    PointsNameTheirHead();
  }
  {
    SCOPED_TRACE("resume");
    SweepResumesFromFinishedRunsAndRefusesIncompatibleOnes();
  }
}

TEST(ReportCli, HelpExitsZeroAndBadUsageTwo) {
  EXPECT_EQ(Invoke(RunReport, {"report", "--help"}), 0);
  EXPECT_EQ(Invoke(RunReport, {"report", "sweep", "--help"}), 0);
  EXPECT_EQ(Invoke(RunReport, {"report", "render", "--help"}), 0);
  EXPECT_EQ(Invoke(RunReport, {"report", "compare", "--help"}), 0);
  EXPECT_EQ(Invoke(RunReport, {"report", "nonsense"}), 2);
  EXPECT_EQ(Invoke(RunReport, {"report", "sweep", "--scene", "builtin", "-o", "/tmp/x"}),
            2);  // no --lambdas
  EXPECT_THROW(Invoke(RunReport, {"report", "sweep", "--scene", "builtin", "--lambdas", "1e-8@0",
                                  "-o", "/tmp/x"}),
               std::invalid_argument);
  EXPECT_EQ(Invoke(RunInfo, {"info", "--help"}), 0);
  EXPECT_EQ(Invoke(RunConformance, {"conformance", "--help"}), 0);
  EXPECT_EQ(Invoke(RunTrain, {"train", "--help"}), 0);
  EXPECT_EQ(Invoke(RunEval, {"eval", "--help"}), 0);
  EXPECT_EQ(Invoke(RunRender, {"render", "--help"}), 0);
}

TEST(ReportReference, BorrowedFromTheSameScheduleOrThePresetsOwn) {
  const testing_util::ScopedTempDir tmp("ecrf_report_ref");
  const std::string dir = tmp.path();
  const nlohmann::json sweep_3000 = {{"preset", "fast"},    {"iterations", 3000},
                                     {"seed", 7},           {"test_view_stride", 10},
                                     {"max_test_views", 0}, {"downscale", 1}};
  nlohmann::json earlier = {{"data", "/data/chair"},
                            {"sweep", sweep_3000},
                            {"reference", {{"float32_bytes", 100}, {"float_psnr", 35.0}}},
                            {"points", nlohmann::json::array()}};
  WriteTextFile(dir + "/report.json", earlier.dump());
  auto borrow = [&](const std::string& key, const nlohmann::json& value) {
    nlohmann::json sweep = sweep_3000;
    sweep[key] = value;
    return BorrowReference(dir, sweep, "/data/chair");
  };
  // A longer schedule measures against the preset's 3000-iteration reference, and says so.
  const nlohmann::json ref = borrow("iterations", 4500);
  EXPECT_EQ(ref["float32_bytes"], 100);
  EXPECT_NE(ref["label"].get<std::string>().find("3000 iterations"), std::string::npos);
  EXPECT_EQ(borrow("iterations", 3000)["float_psnr"], 35.0);
  auto refused = [&](const std::string& key, const nlohmann::json& value, const std::string& why) {
    try {
      borrow(key, value);
      ADD_FAILURE() << key << " " << value.dump() << " was borrowed";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  refused("seed", 8, "its sweep has seed 7, this one 8");
  refused("test_view_stride", 20, "test_view_stride 10, this one 20");
  refused("preset", "paper", "preset \"fast\", this one \"paper\"");
  EXPECT_THROW(BorrowReference(dir, sweep_3000, "/data/mic"), std::runtime_error);
  // A reference that is neither the preset's schedule nor the sweep's does not apply.
  earlier["sweep"]["iterations"] = 2000;
  WriteTextFile(dir + "/report.json", earlier.dump());
  refused("iterations", 4500, "its sweep has iterations 2000, this one 4500");
  EXPECT_EQ(borrow("iterations", 2000)["float32_bytes"], 100);
}

TEST(ReportReference, APointWithoutAFloatScoreHasNoQuantizationLoss) {
  // A run trained by `ecrf train` without --score-float, reused by a sweep: its float PSNR is
  // null; the ratio and the loss against the borrowed reference still exist.
  nlohmann::json report = {
      {"borrowed_reference", {{"float32_bytes", 1000.0}, {"float_psnr", 35.0}}},
      {"points",
       {{{"lambda_e", 3e-11},
         {"file_bytes", 10.0},
         {"decoded_psnr", 35.5},
         {"float_psnr", nullptr},
         {"float32_bytes", 2000.0}}}}};
  AddReferenceColumns(&report);
  const nlohmann::json& p = report["points"][0];
  EXPECT_TRUE(p["quantization_loss_db"].is_null());
  EXPECT_DOUBLE_EQ(p["ratio"].get<double>(), 100.0);
  EXPECT_DOUBLE_EQ(p["psnr_loss_db"].get<double>(), 0.5);
}

TEST(ReportAnchors, OneScenesFiguresOnItsOwnReportAndAveragesOnEvery) {
  const testing_util::ScopedTempDir tmp("ecrf_report_anchors");
  const std::string path = tmp.path() + "/anchors.json";
  WriteTextFile(path, R"({"anchors": [
      {"label": "chair only", "scene": "Chair", "file_bytes": 7e7, "psnr": 35.76},
      {"label": "mic only", "scene": "mic", "file_bytes": 7e7, "psnr": 34.61},
      {"label": "average", "file_bytes": 8e5, "psnr": 32.2},
      {"label": "relative", "ratio": 28.4, "psnr_loss_db": -0.1}]})");
  auto labels = [&](const std::string& scene) {
    std::vector<std::string> out;
    for (const nlohmann::json& a : ReadAnchors(path, scene)) out.push_back(a["label"]);
    return out;
  };
  EXPECT_EQ(labels("chair"), (std::vector<std::string>{"chair only", "average", "relative"}));
  EXPECT_EQ(labels("mic"), (std::vector<std::string>{"mic only", "average", "relative"}));
  EXPECT_EQ(labels("lego"), (std::vector<std::string>{"average", "relative"}));
  EXPECT_TRUE(ReadAnchors("", "chair").empty());
  // The committed file of the 800x800 protocol parses and gives chair its TensoRF figure.
  const nlohmann::json committed =
      ReadAnchors(ECRF_SOURCE_DIR "/docs/reports/anchors_synthetic_800.json", "chair");
  ASSERT_FALSE(committed.empty());
  EXPECT_EQ(committed[0]["psnr"], 35.76);
  // An anchor that cannot be drawn is refused, named by the file and its index.
  const std::vector<std::pair<std::string, std::string>> bad = {
      {R"({"anchors": [{"label": "a", "file_bytes": 1, "psnr": 30}, {"label": "b", "psnr": 30}]})",
       "anchor 1 needs"},
      {R"({"anchors": [{"label": "a", "scene": 3, "file_bytes": 1, "psnr": 30}]})",
       "anchor 0 needs"},
      {R"({"anchors": {"label": "a"}})", "expected {\"anchors\": ["}};
  for (const auto& [text, why] : bad) {
    WriteTextFile(path, text);
    try {
      ReadAnchors(path, "chair");
      ADD_FAILURE() << text;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path + ": " + why), std::string::npos) << e.what();
    }
  }
}

TEST(ReportCli, UnwritableOutputFailsBeforeTraining) {
  // A path below a regular file can never be created: the sweep must say so at once.
  char tmpl[] = "/tmp/ecrf_report_file_XXXXXX";
  const int fd = mkstemp(tmpl);
  ASSERT_GE(fd, 0);
  close(fd);
  try {
    Invoke(RunReport, {"report", "sweep", "--scene", "builtin", "--lambdas", "0", "-o",
                       std::string(tmpl) + "/r"});
    ADD_FAILURE() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("cannot create directory"), std::string::npos) << e.what();
  }
  std::remove(tmpl);
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
