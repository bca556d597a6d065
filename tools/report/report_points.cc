// Rate points of a report: what a finished training run measured, and the columns that compare
// each point with the lambda = 0 float32 model of the same sweep.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "format/mlp_coder.h"
#include "tools/report/report.h"
#include "trainer/data/file_io.h"
#include "trainer/train/checkpoint.h"

namespace ecrf {
namespace tools {

std::string LambdaText(double lambda, double step_scale) {
  char text[64];
  if (std::fabs(step_scale - 1.0) < 1e-6) {
    std::snprintf(text, sizeof(text), "lambda_%g", lambda);
  } else {
    std::snprintf(text, sizeof(text), "lambda_%g_steps%g", lambda, step_scale);
  }
  return text;
}

nlohmann::json RatePointFromMetrics(const nlohmann::json& m, const std::string& run_dir) {
  // A --target-size run starts from lambda_e 0 ("choose one") and adapts it: its point is the
  // lambda_e it ended with, never a lambda = 0 reference.
  const bool sized = m.value("target_bytes", 0.0) > 0.0;
  const double lambda = m.at(sized ? "final_lambda_e" : "lambda_e").get<double>();
  const double step_scale = m.value("quant_step_scale", 1.0);
  nlohmann::json p;
  char label[64];
  if (std::fabs(step_scale - 1.0) < 1e-6) {
    std::snprintf(label, sizeof(label), "lambda=%g", lambda);
  } else {
    std::snprintf(label, sizeof(label), "lambda=%g steps x%g", lambda, step_scale);
  }
  p["label"] = label;
  p["lambda_e"] = lambda;
  p["quant_step_scale"] = step_scale;
  if (sized) p["target_bytes"] = m.at("target_bytes");
  p["run_dir"] = run_dir;
  p["iterations"] = m.at("iterations");
  p["train_seconds"] = m.at("train_seconds");
  p["file_bytes"] = m.at("file_bytes");
  p["decoded_psnr"] = m.at("decoded_test_psnr");
  p["decoded_ssim"] = m.at("decoded_test_ssim");
  p["float_psnr"] = m.at("test_psnr");
  p["float_ssim"] = m.at("test_ssim");
  p["test_views"] = m.at("test_views");
  p["test_image_size"] = m.value("test_image_size", nlohmann::json());  // absent before #58
  p["float32_bytes"] = m.at("float32_model_bytes");
  p["decode_seconds"] = m.value("decode_seconds", 0.0);
  p["decoded_render_seconds_per_view"] = m.value("decoded_render_seconds_per_view", 0.0);
  // What a view of the file costs (#57): its head and spacing, the decoder's work per pixel.
  // Named as AppearanceName names a file's head: runs from before the sh head had its own name
  // wrote the head kind alone ("deferred" with hidden 0).
  std::string head = m.value("head", "mlp");
  for (int k = 0; k < kNumHeadKinds; ++k) {
    if (m.value("mlp_hidden", -1) == 0 && head == kHeadKindNames[k])
      head = AppearanceName(static_cast<HeadKind>(k), 0);
  }
  p["head"] = head;
  p["step_ratio"] = m.value("step_ratio", 0.5);
  p["decoded_work_per_pixel"] = m.value("decoded_work_per_pixel", 0.0);
  p["decoded_samples_per_ray"] = m.value("decoded_samples_per_ray", 0.0);
  p["estimated_grid_bytes"] = m.value("estimated_grid_bytes", 0.0);
  p["grid_res"] = m.value("grid_res", nlohmann::json::array());
  const nlohmann::json& e = m.at("encode");
  nlohmann::json chunks = nlohmann::json::object();
  for (const auto& [name, t] : e.at("tensors").items()) chunks[name] = t.at("bytes");
  chunks["MLPW"] = e.at("mlp_bytes");
  chunks["OCCU"] = e.at("occupancy_bytes");
  chunks["HEAD"] = e.at("head_bytes");
  chunks["meta"] = e.at("metadata_bytes");
  chunks["container"] = e.at("container_bytes");
  p["chunks"] = chunks;
  p["coefficient_bytes"] = e.at("coefficient_bytes");
  nlohmann::json curve = nlohmann::json::array();
  for (const auto& c : m.value("psnr_curve", nlohmann::json::array())) {
    curve.push_back({c.at("minutes"), c.at("test_psnr")});
  }
  p["curve"] = curve;
  return p;
}

void AddReferenceColumns(nlohmann::json* report) {
  nlohmann::json& points = (*report)["points"];
  std::sort(points.begin(), points.end(), [](const nlohmann::json& a, const nlohmann::json& b) {
    const double la = a.at("lambda_e").get<double>(), lb = b.at("lambda_e").get<double>();
    if (la != lb) return la < lb;
    return a.value("quant_step_scale", 1.0) < b.value("quant_step_scale", 1.0);
  });
  nlohmann::json ref;
  for (const nlohmann::json& p : points) {
    if (p.at("lambda_e").get<double>() == 0.0) {
      ref = {{"label", "lambda=0 float32 model"},
             {"float32_bytes", p.at("float32_bytes")},
             {"float_psnr", p.at("float_psnr")},
             {"float_ssim", p.at("float_ssim")}};
    }
  }
  // A sweep without a lambda = 0 point may borrow that reference from an earlier sweep of the
  // same scene and preset (`report sweep --reference`): its float model does not depend on
  // anything the rate points change.
  if (ref.is_null() && report->contains("borrowed_reference"))
    ref = (*report)["borrowed_reference"];
  (*report)["reference"] = ref;
  for (nlohmann::json& p : points) {
    const double bytes = p.at("file_bytes").get<double>();
    const double float32 = (ref.is_null() ? p : ref).at("float32_bytes").get<double>();
    p["ratio"] = float32 / bytes;
    // Runs trained without --score-float have no float PSNR (null), so no quantization loss.
    p["quantization_loss_db"] =
        p.at("float_psnr").is_null()
            ? nlohmann::json()
            : nlohmann::json(p.at("decoded_psnr").get<double>() - p.at("float_psnr").get<double>());
    if (!ref.is_null()) {
      p["psnr_loss_db"] = p.at("decoded_psnr").get<double>() - ref.at("float_psnr").get<double>();
    } else {
      p["psnr_loss_db"] = nullptr;
    }
  }
}

std::vector<RdPoint> RateDistortionCurve(const nlohmann::json& report) {
  std::vector<RdPoint> curve;
  for (const nlohmann::json& p : report.at("points")) {
    RdPoint q;
    q.rate = p.at("file_bytes").get<double>();
    q.psnr = p.at("decoded_psnr").get<double>();
    curve.push_back(q);
  }
  return curve;
}

nlohmann::json ReadJsonFile(const std::string& path) {
  const std::vector<uint8_t> bytes = trainer::ReadWholeFile(path);
  nlohmann::json j = nlohmann::json::parse(bytes.begin(), bytes.end(), nullptr, false);
  if (j.is_discarded()) throw std::runtime_error(path + ": not valid JSON");
  return j;
}

nlohmann::json ReadReport(const std::string& path) {
  const bool is_file = path.size() > 5 && path.compare(path.size() - 5, 5, ".json") == 0;
  const std::string file = is_file ? path : path + "/report.json";
  nlohmann::json j = ReadJsonFile(file);
  if (!j.is_object() || !j.contains("points") || !j["points"].is_array()) {
    throw std::runtime_error(file + ": not an ecrf report (no \"points\" array)");
  }
  return j;
}

}  // namespace tools
}  // namespace ecrf
