#include "tools/report/sweep_points.h"

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "tools/cli_args.h"
#include "tools/report/report.h"
#include "trainer/train/train_config.h"

namespace ecrf {
namespace tools {
namespace {

// The items of a comma-separated list, as --rates, --targets and --lambdas give them.
std::vector<std::string> CommaItems(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) items.push_back(item);
  return items;
}

// "316KB,127KB": file sizes, one --target-size run each. The text names the run directory, so it
// is kept to letters, digits and '.'; `ecrf train` parses and checks the size itself.
std::vector<SweepPoint> ParseTargets(const std::string& text) {
  std::vector<SweepPoint> out;
  for (const std::string& item : CommaItems(text)) {
    const bool plain = !item.empty() && std::all_of(item.begin(), item.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '.';
    });
    if (!plain) throw std::invalid_argument("--targets: '" + item + "' is not a size like 316KB");
    SweepPoint p;
    p.target = item;
    out.push_back(p);
  }
  return out;
}

// "low,medium,high": named rate points.
std::vector<SweepPoint> ParseRates(const std::string& text) {
  std::vector<SweepPoint> out;
  for (const std::string& item : CommaItems(text)) {
    trainer::TrainOptions check;
    trainer::ApplyRatePoint(item, &check);  // throws for unknown names
    SweepPoint p;
    p.rate = item;
    out.push_back(p);
  }
  return out;
}

// "0,2e-11@3,1e-10": lambda_e values, each with an optional step scale after '@'.
std::vector<SweepPoint> ParsePoints(const std::string& text) {
  std::vector<SweepPoint> out;
  for (const std::string& item : CommaItems(text)) {
    SweepPoint p;
    const size_t at = item.find('@');
    p.lambda = ParseFloat("--lambdas", item.substr(0, at).c_str());
    if (at != std::string::npos) {
      p.step_scale = ParseFloat("--lambdas (step scale after @)", item.substr(at + 1).c_str());
      if (!(p.step_scale > 0.f))
        throw std::invalid_argument("--lambdas: the step scale after @ must be > 0 in '" + item +
                                    "'");
    }
    bool seen = false;
    for (const SweepPoint& q : out) seen |= q.lambda == p.lambda && q.step_scale == p.step_scale;
    if (!seen) out.push_back(p);
  }
  return out;
}

}  // namespace

std::vector<SweepPoint> ParseSweepPoints(const std::string& rates, const std::string& targets,
                                         const std::string& lambdas) {
  std::vector<SweepPoint> points = ParseRates(rates);
  for (const SweepPoint& p : ParseTargets(targets)) points.push_back(p);
  for (const SweepPoint& p : ParsePoints(lambdas)) points.push_back(p);
  return points;
}

std::vector<std::string> PointArgs(const SweepPoint& p) {
  if (!p.rate.empty()) return {"--rate", p.rate};
  if (!p.target.empty()) return {"--target-size", p.target};
  char text[32];
  std::snprintf(text, sizeof(text), "%.9g", p.lambda);
  std::vector<std::string> args = {"--lambda-e", text};
  if (p.step_scale > 0.f) {
    std::snprintf(text, sizeof(text), "%.9g", double(p.step_scale));
    args.insert(args.end(), {"--quant-step-scale", text});
  }
  return args;
}

std::string PointName(const SweepPoint& p, const trainer::TrainOptions& resolved) {
  if (!p.target.empty()) return "target_" + p.target;
  return p.rate.empty() ? LambdaText(p.lambda, resolved.quant_step_scale) : "rate_" + p.rate;
}

// "../shared/data/chair" and "/work/shared/data/chair" are the same data (relative paths as seen
// from the current directory).
bool SameData(const std::string& a, const std::string& b) {
  if (a == b) return true;
  char ra[PATH_MAX], rb[PATH_MAX];
  return realpath(a.c_str(), ra) && realpath(b.c_str(), rb) && std::strcmp(ra, rb) == 0;
}

// A finished run is reused only when it was trained as this sweep would train it: by its
// config.json when it has one (every setting), else by the metrics older runs recorded.
void CheckReusable(const nlohmann::json& m, const trainer::TrainOptions& o,
                   const std::string& path) {
  const std::string dir = path.substr(0, path.find_last_of('/'));
  if (FileExists(dir + "/config.json")) {
    const trainer::TrainOptions had = trainer::TrainConfigFromJson(
        ReadJsonFile(dir + "/config.json").dump(), dir + "/config.json");
    std::vector<std::string> changed = trainer::ChangedSettings(had, o);
    // The same data under another relative path is the same run.
    changed.erase(std::remove_if(changed.begin(), changed.end(),
                                 [&](const std::string& c) {
                                   return c.rfind("data_dir:", 0) == 0 &&
                                          SameData(had.data_dir, o.data_dir);
                                 }),
                  changed.end());
    if (changed.empty()) return;
    std::string list;
    for (const std::string& c : changed) list += "\n  " + c;
    throw std::runtime_error(dir + ": finished run has other settings than this sweep asks for:" +
                             list + "\nremove that run directory or report into another -o");
  }
  auto mismatch = [&](const std::string& what, const std::string& had, const std::string& want) {
    throw std::runtime_error(path + ": finished run has " + what + " " + had +
                             ", this sweep asks for " + want +
                             "; remove that run directory or report into another -o");
  };
  const std::string& data = trainer::DataSource(o);
  if (m.value("preset", "") != trainer::NameOf(o.preset))
    mismatch("preset", m.value("preset", "?"), trainer::NameOf(o.preset));
  if (!SameData(m.value("data", ""), data)) mismatch("data", m.value("data", "?"), data);
  if (m.value("iterations", -1) != o.iters) {
    mismatch("iterations", std::to_string(m.value("iterations", -1)), std::to_string(o.iters));
  }
  if (m.contains("test_view_stride") && m["test_view_stride"] != o.test_view_stride) {
    mismatch("test stride", m["test_view_stride"].dump(), std::to_string(o.test_view_stride));
  }
  if (m.contains("seed") && m["seed"] != o.seed)
    mismatch("seed", m["seed"].dump(), std::to_string(o.seed));
  // Runs from before these options existed were trained with their defaults (1 and off).
  auto check_float = [&](const char* key, const char* what, float want) {
    const double had = m.value(key, 1.0);
    if (std::fabs(had - want) > 1e-6 * std::fabs(want))
      mismatch(what, std::to_string(had), std::to_string(want));
  };
  check_float("quant_step_scale", "quantization step scale", o.quant_step_scale);
  check_float("qat_start", "quantization-aware start", o.qat_start);
  if (m.value("mlp_levels", 0) != o.mlp_levels) {
    mismatch("MLP levels", std::to_string(m.value("mlp_levels", 0)), std::to_string(o.mlp_levels));
  }
}

}  // namespace tools
}  // namespace ecrf
