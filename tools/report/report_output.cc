// Everything a report directory holds besides its runs, written from report.json alone: the
// CSV behind each plot, the plots (tools/report/plot_report.py, when matplotlib is installed) and
// index.html.
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "tools/cli_args.h"
#include "tools/report/report.h"
#include "trainer/data/file_io.h"
#include "trainer/train/checkpoint.h"

namespace ecrf {
namespace tools {
namespace {

// A JSON number as CSV/HTML text; null and missing values become empty cells.
std::string Num(const nlohmann::json& v, const char* format = "%.10g") {
  if (!v.is_number()) return "";
  char text[64];
  std::snprintf(text, sizeof(text), format, v.get<double>());
  return text;
}

std::string Csv(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string q = "\"";
  for (char c : text) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string Html(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string Str(const nlohmann::json& j, const char* key) {
  return j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : "";
}

std::string RdCsv(nlohmann::json& r) {
  std::ostringstream o;
  o << "label,lambda_e,file_bytes,decoded_psnr,decoded_ssim,float_psnr,float_ssim,ratio,psnr_loss_"
       "db,"
       "float32_bytes,train_seconds,iterations,head,step_ratio,work_per_pixel,seconds_per_view\n";
  for (nlohmann::json& p : r["points"]) {
    o << Csv(Str(p, "label")) << ',' << Num(p["lambda_e"]) << ',' << Num(p["file_bytes"]) << ','
      << Num(p["decoded_psnr"]) << ',' << Num(p["decoded_ssim"]) << ',' << Num(p["float_psnr"])
      << ',' << Num(p["float_ssim"]) << ',' << Num(p["ratio"]) << ',' << Num(p["psnr_loss_db"])
      << ',' << Num(p["float32_bytes"]) << ',' << Num(p["train_seconds"]) << ','
      << Num(p["iterations"]) << ',' << Csv(Str(p, "head")) << ',' << Num(p["step_ratio"]) << ','
      << Num(p["decoded_work_per_pixel"]) << ',' << Num(p["decoded_render_seconds_per_view"])
      << '\n';
  }
  return o.str();
}

std::string ChunksCsv(nlohmann::json& r) {
  std::ostringstream o;
  o << "label,lambda_e,chunk,bytes\n";
  for (nlohmann::json& p : r["points"]) {
    for (const auto& [name, bytes] : p["chunks"].items()) {
      o << Csv(Str(p, "label")) << ',' << Num(p["lambda_e"]) << ',' << Csv(name) << ','
        << Num(bytes) << '\n';
    }
  }
  return o.str();
}

std::string CurveCsv(nlohmann::json& r) {
  std::ostringstream o;
  o << "label,lambda_e,minutes,test_psnr\n";
  for (nlohmann::json& p : r["points"]) {
    for (nlohmann::json& c : p["curve"]) {
      o << Csv(Str(p, "label")) << ',' << Num(p["lambda_e"]) << ',' << Num(c[0]) << ',' << Num(c[1])
        << '\n';
    }
  }
  return o.str();
}

std::string AnchorsCsv(nlohmann::json& r) {
  std::ostringstream o;
  o << "label,file_bytes,psnr,ratio,psnr_loss_db\n";
  for (nlohmann::json& a : r["anchors"]) {
    o << Csv(Str(a, "label")) << ',' << Num(a.value("file_bytes", nlohmann::json())) << ','
      << Num(a.value("psnr", nlohmann::json())) << ',' << Num(a.value("ratio", nlohmann::json()))
      << ',' << Num(a.value("psnr_loss_db", nlohmann::json())) << '\n';
  }
  return o.str();
}

std::string SpeedCsv(nlohmann::json& r) {
  std::ostringstream o;
  o << "knob,setting,is_default,seconds_per_view,psnr,ssim,threads,width,height,samples_per_ray,"
       "mlp_samples_per_ray\n";
  for (nlohmann::json& row : r["speed"]["rows"]) {
    o << Csv(Str(row, "knob")) << ',' << Csv(Str(row, "setting")) << ','
      << (row.value("is_default", false) ? 1 : 0) << ',' << Num(row["seconds_per_view"]) << ','
      << Num(row["psnr"]) << ',' << Num(row["ssim"]) << ',' << Num(row["threads"]) << ','
      << Num(row["width"]) << ',' << Num(row["height"]) << ',' << Num(row["samples_per_ray"]) << ','
      << Num(row["mlp_samples_per_ray"]) << '\n';
  }
  return o.str();
}

std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string PlotScript() {
  if (const char* env = std::getenv("ECRF_PLOT_SCRIPT")) return env;
  return ECRF_PLOT_SCRIPT_DEFAULT;
}

std::string Python() {
  if (const char* env = std::getenv("ECRF_PYTHON")) return env;
  // Debian's interpreter first: its python3-matplotlib is what the README installs, and a python3
  // earlier on PATH (pyenv, a virtualenv) may not have it.
  return FileExists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
}

// Runs the plotting script with `args`; false (and the reason on stderr) when it failed.
bool RunPlotScript(const std::string& args, const std::string& dir) {
  const std::string script = PlotScript();
  if (!FileExists(script)) {
    std::fprintf(stderr, "report: plots skipped: %s not found (set ECRF_PLOT_SCRIPT)\n",
                 script.c_str());
    return false;
  }
  const std::string command = Quote(Python()) + " " + Quote(script) + " " + args + " 1>&2";
  const int status = std::system(command.c_str());
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code == 0) return true;
  if (code == 3) {  // the script's "matplotlib is not installed"
    std::fprintf(stderr,
                 "report: plots skipped; for plots: apt-get install python3-matplotlib, then "
                 "`ecrf report plot %s`\n",
                 dir.c_str());
  } else {
    std::fprintf(
        stderr,
        "report: %s failed (exit status %d, its message is above); the tables and CSV files "
        "are complete\n",
        script.c_str(), code);
  }
  return false;
}

void Row(std::ostringstream& o, std::initializer_list<std::string> cells, const char* tag = "td") {
  o << "<tr>";
  for (const std::string& c : cells) o << '<' << tag << '>' << c << "</" << tag << '>';
  o << "</tr>\n";
}

void Figure(std::ostringstream& o, const std::string& dir, const std::string& png,
            const std::string& csv, const std::string& alt) {
  if (FileExists(dir + "/" + png)) {
    o << "<figure><img src=\"" << png << "\" alt=\"" << Html(alt) << "\"><figcaption>" << Html(alt)
      << " (data: <a href=\"" << csv << "\">" << csv << "</a>)</figcaption></figure>\n";
  } else {
    o << "<p class=note>Plot " << png << " not drawn (needs python3-matplotlib); data in <a href=\""
      << csv << "\">" << csv << "</a>.</p>\n";
  }
}

// Which test views the PSNR and SSIM are over, as published tables need it said: the count and
// image size of the first point that records them (every point scores the same views).
std::string ScoredViewsText(nlohmann::json& r) {
  std::string text =
      "Test PSNR and SSIM (TensoRF's rgb_ssim: 11x11 Gaussian window, sigma 1.5) over ";
  for (nlohmann::json& p : r["points"]) {
    if (!p["test_views"].is_number()) continue;
    text += Num(p["test_views"]) + " test views";
    nlohmann::json& size = p["test_image_size"];
    if (size.is_array() && size.size() == 2) text += " of " + Num(size[0]) + "x" + Num(size[1]);
    return text + " (view stride " + Num(r["sweep"]["test_view_stride"]) +
           ", 0: at most 20 views); MB = 10^6 bytes.";
  }
  return text + "the test views with stride " + Num(r["sweep"]["test_view_stride"]) + ".";
}

// The page's head and style, the scene, and what the sweep trained, where and with which ecrf.
void HtmlHead(std::ostringstream& o, nlohmann::json& r) {
  const std::string scene = Html(Str(r, "scene"));
  o << "<!doctype html>\n<html lang=en><head><meta charset=utf-8>"
       "<meta name=viewport content=\"width=device-width, initial-scale=1\">\n<title>ecrf report: "
    << scene
    << "</title>\n<style>body{font:15px/1.45 system-ui,sans-serif;max-width:1100px;margin:2em auto;"
       "padding:0 1em;color:#222}table{border-collapse:collapse;margin:1em "
       "0;font-variant-numeric:tabular-nums}"
       "td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}th{background:#f3f3f3}"
       "td:first-child,th:first-child{text-align:left}img{max-width:100%}figure{margin:1em 0}"
       ".note{color:#666}tr.default{font-weight:600}</style></head><body>\n";
  o << "<h1>ecrf report: " << scene << "</h1>\n";
  nlohmann::json& s = r["sweep"];
  o << "<p>Data <code>" << Html(Str(r, "data")) << "</code>, preset <code>"
    << Html(Str(s, "preset")) << "</code>, " << Num(s["iterations"]) << " iterations per run. "
    << ScoredViewsText(r) << " ecrf " << Html(Str(r, "ecrf_version")) << " (bitstream "
    << Num(r["bitstream_version"]) << "), " << Html(Str(r, "date")) << ", "
    << Html(Str(r["machine"], "cpu")) << ", "
    << "training threads: " << Num(s["threads"])
    << ". All numbers in <a href=\"report.json\">report.json</a>.</p>\n";
}

// Bytes as the published tables count them: MB of 10^6 bytes, three decimals.
std::string Megabytes(const nlohmann::json& bytes) {
  return bytes.is_number() ? Num(nlohmann::json(bytes.get<double>() / 1e6), "%.3f") : Num(bytes);
}

// The rate–distortion plots, one table row per point, and the anchors drawn beside them.
void RateDistortionSection(std::ostringstream& o, const std::string& dir, nlohmann::json& r) {
  o << "<h2>Rate–distortion</h2>\n<p>Each point is one training run at rate weight lambda_e, "
       "encoded to a "
       ".ecrf file and scored after decoding it with the embeddable decoder. Ratio and loss are "
       "against the "
       "lambda = 0 float32 model";
  if (!r["reference"].is_null()) {
    o << " (" << Num(r["reference"]["float32_bytes"], "%.0f") << " bytes, "
      << Num(r["reference"]["float_psnr"], "%.2f") << " dB)";
  }
  o << "; the quantization loss is the decoded file against its own float model.</p>\n";
  Figure(o, dir, "rd.png", "rd.csv", "file size vs PSNR of the decoded file");
  Figure(o, dir, "ratio.png", "rd.csv", "compression ratio vs PSNR loss");
  bool costs = false;  // reports from before #57 have none
  for (nlohmann::json& p : r["points"]) costs |= p.value("decoded_work_per_pixel", 0.0) > 0.0;
  if (costs) Figure(o, dir, "cost.png", "rd.csv", "work per pixel and render time vs PSNR");
  o << "<table>\n";
  Row(o,
      {"point", "file bytes", "MB", "ratio", "decoded PSNR", "SSIM", "float PSNR",
       "quantization loss", "loss vs lambda=0", "train min", "head", "work/pixel", "ms/view"},
      "th");
  for (nlohmann::json& p : r["points"]) {
    Row(o, {Html(Str(p, "label")), Num(p["file_bytes"], "%.0f"), Megabytes(p["file_bytes"]),
            Num(p["ratio"], "%.1fx"), Num(p["decoded_psnr"], "%.2f dB"),
            Num(p["decoded_ssim"], "%.4f"), Num(p["float_psnr"], "%.2f dB"),
            Num(p["quantization_loss_db"], "%+.2f dB"), Num(p["psnr_loss_db"], "%+.2f dB"),
            Num(nlohmann::json(p["train_seconds"].get<double>() / 60.0), "%.1f"),
            Html(Str(p, "head")), Num(p["decoded_work_per_pixel"], "%.0f"),
            Num(p["decoded_render_seconds_per_view"].is_number()
                    ? nlohmann::json(p["decoded_render_seconds_per_view"].get<double>() * 1e3)
                    : nlohmann::json(),
                "%.0f")});
  }
  o << "</table>\n";
  if (!r["anchors"].empty()) {
    o << "<h3>Anchors</h3>\n<table>\n";
    Row(o, {"anchor", "file bytes", "MB", "PSNR", "ratio", "loss", "note"}, "th");
    for (nlohmann::json& a : r["anchors"]) {
      Row(o, {Html(Str(a, "label")), Num(a.value("file_bytes", nlohmann::json()), "%.0f"),
              Megabytes(a.value("file_bytes", nlohmann::json())),
              Num(a.value("psnr", nlohmann::json()), "%.2f dB"),
              Num(a.value("ratio", nlohmann::json()), "%.1fx"),
              Num(a.value("psnr_loss_db", nlohmann::json()), "%+.2f dB"), Html(Str(a, "note"))});
    }
    o << "</table>\n";
  }
}

// The bytes of each point's file by chunk: density and appearance coefficients, MLP, occupancy,
// the rest.
void ChunkSection(std::ostringstream& o, const std::string& dir, nlohmann::json& r) {
  o << "<h2>Where the bytes go</h2>\n";
  Figure(o, dir, "chunks.png", "chunks.csv", "bytes per chunk");
  o << "<table>\n";
  Row(o, {"point", "density COEF", "appearance COEF", "MLPW", "OCCU", "HEAD + meta + container"},
      "th");
  for (nlohmann::json& p : r["points"]) {
    double density = 0, appearance = 0, other = 0;
    for (const auto& [name, bytes] : p["chunks"].items()) {
      const double b = bytes.get<double>();
      if (name.rfind("density.", 0) == 0)
        density += b;
      else if (name.rfind("appearance.", 0) == 0)
        appearance += b;
      else if (name != "MLPW" && name != "OCCU")
        other += b;
    }
    Row(o, {Html(Str(p, "label")), Num(nlohmann::json(density), "%.0f"),
            Num(nlohmann::json(appearance), "%.0f"), Num(p["chunks"]["MLPW"], "%.0f"),
            Num(p["chunks"]["OCCU"], "%.0f"), Num(nlohmann::json(other), "%.0f")});
  }
  o << "</table>\n";
}

// The speed–error sweep of `ecrf report render` (when the report has one): decoding time and
// each renderer knob's time and error.
void SpeedSection(std::ostringstream& o, const std::string& dir, nlohmann::json& sp) {
  nlohmann::json& d = sp["decode"];
  o << "<h2>Speed against error</h2>\n<p>Renderer knobs of SPEC.md 7.8, one at a time from the "
       "defaults, on "
    << Html(Str(sp, "file")) << " (" << Html(Str(sp, "point")) << ", "
    << Num(sp["file_bytes"], "%.0f") << " bytes), " << Num(sp["views"]) << " test views (stride "
    << Num(sp["test_view_stride"])
    << "). Image scale 1/k renders at 1/k of the size and scores the bilinear upsampling.</p>\n";
  o << "<p>Decoding (entropy decoding + integer IDCT + grid layout, one thread, fastest of 3): "
    << Num(d["float32_seconds"], "%.3f") << " s to float32 grids ("
    << Num(d["float32_ms_per_mb"], "%.0f") << " ms per MB of stream, "
    << Num(nlohmann::json(d["float32_grid_bytes"].get<double>() / 1e6), "%.1f") << " MB of grids), "
    << Num(d["int16_seconds"], "%.3f") << " s to int16 grids ("
    << Num(nlohmann::json(d["int16_grid_bytes"].get<double>() / 1e6), "%.1f") << " MB)";
  if (d["peak_rss_growth_bytes"].is_number()) {
    o << "; peak RSS grew by "
      << Num(nlohmann::json(d["peak_rss_growth_bytes"].get<double>() / 1e6), "%.1f")
      << " MB while decoding to float32 (stream and grids)";
  }
  o << ".</p>\n";
  Figure(o, dir, "speed.png", "speed.csv", "render time per view vs PSNR");
  o << "<table>\n";
  Row(o,
      {"knob", "setting", "ms/view", "PSNR", "SSIM", "threads", "size", "samples/ray",
       "MLP samples/ray"},
      "th");
  for (nlohmann::json& row : sp["rows"]) {
    if (row.value("is_default", false)) o << "<tr class=default>";
    std::ostringstream line;
    Row(line, {Html(Str(row, "knob")), Html(Str(row, "setting")),
               Num(nlohmann::json(1e3 * row["seconds_per_view"].get<double>()), "%.1f"),
               Num(row["psnr"], "%.2f dB"), Num(row["ssim"], "%.4f"), Num(row["threads"]),
               Num(row["width"]) + "x" + Num(row["height"]), Num(row["samples_per_ray"], "%.1f"),
               Num(row["mlp_samples_per_ray"], "%.2f")});
    std::string text = line.str();
    if (row.value("is_default", false)) text = text.substr(4);
    o << text;
  }
  o << "</table>\n";
}

std::string IndexHtml(const std::string& dir, nlohmann::json& r) {
  std::ostringstream o;
  HtmlHead(o, r);
  RateDistortionSection(o, dir, r);
  ChunkSection(o, dir, r);
  o << "<h2>Training curve</h2>\n<p>Test PSNR of the float model against wall-clock training "
       "minutes "
       "(evaluation time excluded).</p>\n";
  Figure(o, dir, "curve.png", "curve.csv", "test PSNR vs training minutes");
  if (r.contains("speed")) SpeedSection(o, dir, r["speed"]);
  o << "<p class=note>Rebuild: <code>ecrf report sweep ... -o DIR</code> (finished runs are "
       "reused), "
       "<code>ecrf report render DIR</code>, <code>ecrf report plot DIR</code>; compare two "
       "reports with "
       "<code>ecrf report compare A/report.json B/report.json</code>.</p>\n</body></html>\n";
  return o.str();
}

bool DrawPlots(const std::string& dir) { return RunPlotScript(Quote(dir), dir); }

}  // namespace

std::string CompareCsv(const std::vector<std::pair<std::string, nlohmann::json>>& reports) {
  std::ostringstream o;
  o << "series,file_bytes,psnr,left_out,work_per_pixel,seconds_per_view\n";
  for (const auto& [name, report] : reports) {
    std::vector<RdPoint> dominated;
    ParetoFront(RateDistortionCurve(report), &dominated);
    for (const nlohmann::json& p : report.at("points")) {
      const RdPoint q{p.at("file_bytes").get<double>(), p.at("decoded_psnr").get<double>()};
      bool left_out = false;
      for (const RdPoint& d : dominated) left_out |= d.rate == q.rate && d.psnr == q.psnr;
      o << Csv(name) << ',' << Num(nlohmann::json(q.rate), "%.0f") << ','
        << Num(nlohmann::json(q.psnr), "%.6f") << ',' << (left_out ? 1 : 0) << ','
        << Num(p.value("decoded_work_per_pixel", nlohmann::json())) << ','
        << Num(p.value("decoded_render_seconds_per_view", nlohmann::json())) << '\n';
    }
  }
  return o.str();
}

void WriteTextFile(const std::string& path, const std::string& text) {
  trainer::WriteFileAtomically(path, text.data(), text.size());
}

bool DrawComparePlot(const std::string& png, const std::string& csv) {
  std::remove(png.c_str());
  return RunPlotScript("--compare " + Quote(png) + " " + Quote(csv), png) && FileExists(png);
}

bool WriteReport(const std::string& dir, const nlohmann::json& written) {
  WriteTextFile(dir + "/report.json", written.dump(2) + "\n");
  // The writers below read a copy in which every key they use exists (null when unknown).
  nlohmann::json report = written;
  for (const char* key : {"anchors", "points"}) {
    if (!report[key].is_array()) report[key] = nlohmann::json::array();
  }
  WriteTextFile(dir + "/rd.csv", RdCsv(report));
  WriteTextFile(dir + "/chunks.csv", ChunksCsv(report));
  WriteTextFile(dir + "/curve.csv", CurveCsv(report));
  if (!report["anchors"].empty()) WriteTextFile(dir + "/anchors.csv", AnchorsCsv(report));
  if (report.contains("speed")) WriteTextFile(dir + "/speed.csv", SpeedCsv(report));
  const bool plots = DrawPlots(dir);
  WriteTextFile(dir + "/index.html", IndexHtml(dir, report));
  return plots;
}

}  // namespace tools
}  // namespace ecrf
