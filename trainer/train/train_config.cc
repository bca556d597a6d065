#include "trainer/train/train_config.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace ecrf {
namespace trainer {
namespace {

using Json = nlohmann::json;

// Every field that changes what a run trains or writes. A field added to TrainOptions that
// changes results belongs here (tests/trainer/train_config_test.cc checks the round trip).
template <class F>
void VisitSettings(TrainOptions& o, F&& f) {
  f("preset", o.preset);
  f("rate_point", o.rate_point);
  f("data_dir", o.data_dir);
  f("procedural_scene", o.procedural_scene);
  f("scene_type", o.scene_type);
  f("downscale", o.downscale);
  f("seed", o.seed);
  f("iters", o.iters);
  f("reference_iters", o.reference_iters);
  f("batch_rays", o.batch_rays);
  f("voxels_init", o.voxels_init);
  f("voxels_final", o.voxels_final);
  f("upsample_iters", o.upsample_iters);
  f("alpha_mask_iters", o.alpha_mask_iters);
  f("mask_downscale", o.mask_downscale);
  f("lr_grid", o.lr_grid);
  f("lr_network", o.lr_network);
  f("lr_decay_ratio", o.lr_decay_ratio);
  f("l1_weight_initial", o.l1_weight_initial);
  f("l1_weight_rest", o.l1_weight_rest);
  f("max_samples_per_ray", o.max_samples_per_ray);
  f("distortion_weight", o.distortion_weight);
  f("tv_weight_density", o.tv_weight_density);
  f("tv_weight_app", o.tv_weight_app);
  f("exposure_codes", o.exposure_codes);
  f("lr_exposure", o.lr_exposure);
  f("refine_cameras", o.refine_cameras);
  f("refine_cameras_every", o.refine_cameras_every);
  f("camera_warmup_iters", o.camera_warmup_iters);
  f("weight_threshold", o.weight_threshold);
  f("fine_grid_at_rate_points", o.fine_grid_at_rate_points);
  f("density_rank", o.density_rank);
  f("appearance_rank", o.appearance_rank);
  f("mlp_hidden", o.mlp_hidden);
  f("lambda_e", o.lambda_e);
  f("alpha", o.alpha);
  f("plane_block", o.plane_block);
  f("line_block", o.line_block);
  f("rate_fraction", o.rate_fraction);
  f("rate_start", o.rate_start);
  f("entropy_lr", o.entropy_lr);
  f("coef_bits", o.coef_bits);
  f("quant_step_scale", o.quant_step_scale);
  f("density_step_factor", o.density_step_factor);
  f("qat_start", o.qat_start);
  f("rounding_offset", o.rounding_offset);
  f("rdoq_lambda", o.rdoq_lambda);
  f("qat_refresh", o.qat_refresh);
  f("prune_at", o.prune_at);
  f("prune_share", o.prune_share);
  f("prune_rays", o.prune_rays);
  f("mlp_levels", o.mlp_levels);
  f("target_bytes", o.target_bytes);
  f("rate_control_every", o.rate_control_every);
  f("builtin_size", o.builtin_size);
  f("builtin_views", o.builtin_views);
  f("capture_width", o.capture_width);
  f("capture_height", o.capture_height);
  f("capture_frames", o.capture_frames);
}

// Where a run writes and how it is scored: free to change between commands on one run.
template <class F>
void VisitBookkeeping(TrainOptions& o, F&& f) {
  f("out_dir", o.out_dir);
  f("checkpoint_every", o.checkpoint_every);
  f("resume", o.resume);
  f("stop_after", o.stop_after);
  f("eval_every", o.eval_every);
  f("test_view_stride", o.test_view_stride);
  f("max_test_views", o.max_test_views);
  f("eval_downscale", o.eval_downscale);
  f("score_float", o.score_float);
  f("save_renders", o.save_renders);
  f("progress_every", o.progress_every);
}

// The shortest decimal that reads back as the same float: config.json says 3e-11, not
// 2.9999999848243206e-11, and reading it back gives the identical float.
Json FloatJson(float v) {
  char text[32];
  for (int digits = 1; digits <= 9; ++digits) {
    std::snprintf(text, sizeof(text), "%.*g", digits, double(v));
    if (std::strtof(text, nullptr) == v) break;
  }
  return Json::parse(text);
}

struct Writer {
  Json* out;
  void operator()(const char* key, float& v) const { (*out)[key] = FloatJson(v); }
  void operator()(const char* key, int (&v)[3]) const { (*out)[key] = {v[0], v[1], v[2]}; }
  template <class T>
  void operator()(const char* key, T& v) const {
    (*out)[key] = v;
  }
};

struct Reader {
  const Json* in;
  const std::string* where;
  template <class T>
  void Read(const char* key, T* v) const {
    if (!in->contains(key)) return;
    try {
      in->at(key).get_to(*v);
    } catch (const nlohmann::json::exception& e) {
      throw std::runtime_error(*where + ": config field '" + key + "': " + e.what());
    }
  }
  void operator()(const char* key, int (&v)[3]) const {
    std::vector<int> shape;
    Read(key, &shape);
    if (!in->contains(key)) return;
    if (shape.size() != 3)
      throw std::runtime_error(*where + ": config field '" + key + "' is not 3 integers");
    for (int k = 0; k < 3; ++k) v[k] = shape[size_t(k)];
  }
  template <class T>
  void operator()(const char* key, T& v) const {
    Read(key, &v);
  }
};

Json ToJson(const TrainOptions& options) {
  TrainOptions o = options;
  Json settings = Json::object(), bookkeeping = Json::object();
  VisitSettings(o, Writer{&settings});
  VisitBookkeeping(o, Writer{&bookkeeping});
  return Json{{"config_version", kTrainConfigVersion},
              {"settings", settings},
              {"bookkeeping", bookkeeping}};
}

}  // namespace

std::string TrainConfigToJson(const TrainOptions& options, int indent) {
  return ToJson(options).dump(indent);
}

TrainOptions TrainConfigFromJson(const std::string& text, const std::string& where) {
  Json j;
  try {
    j = Json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(where + ": not a run configuration (" + e.what() + ")");
  }
  if (!j.is_object() || !j.contains("settings") || !j["settings"].is_object()) {
    throw std::runtime_error(where + ": not a run configuration (no \"settings\" object)");
  }
  const int version = j.value("config_version", 0);
  if (version > kTrainConfigVersion) {
    throw std::runtime_error(where + ": config_version " + std::to_string(version) +
                             " is newer than this ecrf reads (" +
                             std::to_string(kTrainConfigVersion) + ")");
  }
  const Json& settings = j["settings"];
  TrainOptions o = PresetOptions(settings.value("preset", std::string("fast")));
  VisitSettings(o, Reader{&settings, &where});
  if (j.contains("bookkeeping") && j["bookkeeping"].is_object()) {
    VisitBookkeeping(o, Reader{&j["bookkeeping"], &where});
  }
  return o;
}

std::vector<std::string> ChangedSettings(const TrainOptions& before, const TrainOptions& after) {
  const Json a = ToJson(before)["settings"], b = ToJson(after)["settings"];
  std::vector<std::string> changed;
  for (auto it = a.begin(); it != a.end(); ++it) {
    const Json& other = b.at(it.key());
    if (*it != other) changed.push_back(it.key() + ": " + it->dump() + " -> " + other.dump());
  }
  return changed;
}

}  // namespace trainer
}  // namespace ecrf
