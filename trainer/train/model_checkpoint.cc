// Model checkpoints: the grids, the head, the alpha mask and the rate state, with the
// configuration that rebuilds the model, written and read with their sanity checks.
#include <algorithm>
#include <cmath>
#include <new>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <utility>

#include "encoder/coef_rdoq.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/rate_state.h"
#include "trainer/train/train_config.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace trainer {

void SaveModelCheckpoint(const std::string& path, TensorfModel& model, int iteration,
                         const TrainOptions& o, const RateState* rate,
                         const Checkpoint* train_state, const TrainOptions* config) {
  Checkpoint ck;
  nlohmann::json j;
  j["format"] = "ecrf-checkpoint-1";
  j["iteration"] = iteration;
  j["preset"] = NameOf(o.preset);
  j["iters"] = o.iters;
  j["lambda_e"] = o.lambda_e;  // the live value under rate control
  j["rate_control_last_bytes"] = rate ? rate->rate_control_last_bytes : 0;
  j["rounding_offset"] = o.rounding_offset;  // the quantizer the run trained through
  j["rdoq_lambda"] = o.rdoq_lambda;
  j["res"] = model.res();
  j["aabb_min"] = model.aabb().min;
  j["aabb_max"] = model.aabb().max;
  j["n_samples"] = model.n_samples();
  j["density_rank"] = model.config().density_ranks;
  j["appearance_rank"] = model.config().app_ranks;
  const TensorfConfig& c = model.config();
  j["render"] = {{"near", c.near},
                 {"far", c.far},
                 {"white_background", c.white_background},
                 {"density_shift", c.density_shift},
                 {"density_activation", DensityActivationName(c.density_activation)},
                 {"distance_scale", c.distance_scale},
                 {"step_ratio", c.step_ratio},
                 {"weight_threshold", c.weight_threshold},
                 {"early_stop", c.early_stop_transmittance},
                 {"scene_model", static_cast<int>(c.scene_model)},
                 {"roi_min", c.roi.min},
                 {"roi_max", c.roi.max}};
  if (c.scene_model == SceneModel::kForward) {
    j["render"]["ndc_world_to_ref"] =
        std::vector<float>(c.ndc.world_to_ref, c.ndc.world_to_ref + 12);
    j["render"]["ndc_scale"] = std::vector<float>(c.ndc.scale, c.ndc.scale + 2);
    j["render"]["ndc_near_plane"] = c.ndc.near_plane;
  }
  j["head"] = {
      {"feature_dim", c.head.feature_dim},           {"feature_pe_freqs", c.head.feature_pe_freqs},
      {"viewdir_pe_freqs", c.head.viewdir_pe_freqs}, {"hidden", c.head.hidden},
      {"hidden_layers", c.head.hidden_layers},       {"kind", HeadKindName(c.head.kind)}};
  if (const AlphaMask* mask = model.alpha_mask()) {
    j["mask_res"] = mask->res();
    j["mask_aabb_min"] = mask->aabb().min;
    j["mask_aabb_max"] = mask->aabb().max;
    CheckpointArray occ{"alpha_mask", {int64_t(mask->occupancy().size())}, {}};
    occ.data.assign(mask->occupancy().begin(), mask->occupancy().end());
    ck.arrays.push_back(std::move(occ));
  }
  // The block shapes of the run, so that `ecrf encode` codes with the blocks training used.
  j["plane_block"] = rate && rate->active
                         ? std::vector<int>(rate->config.plane_block, rate->config.plane_block + 3)
                         : std::vector<int>(o.plane_block.begin(), o.plane_block.end());
  j["line_block"] = rate && rate->active
                        ? std::vector<int>(rate->config.line_block, rate->config.line_block + 3)
                        : std::vector<int>(o.line_block.begin(), o.line_block.end());
  if (rate && rate->active) {
    j["rate_active"] = true;
    ck.arrays.push_back({"rate.steps", {int64_t(rate->steps.size())}, rate->steps});
    ck.arrays.push_back(
        {"rate.entropy_model", {int64_t(rate->entropy.params().size())}, rate->entropy.params()});
  }
  if (config) j["config"] = nlohmann::json::parse(TrainConfigToJson(*config, -1));
  if (train_state) {
    j["train_state"] = nlohmann::json::parse(train_state->json);
    ck.arrays.insert(ck.arrays.end(), train_state->arrays.begin(), train_state->arrays.end());
  }
  ck.json = j.dump();
  for (const NamedArray& a : model.NamedParameters()) {
    ck.arrays.push_back({a.name, a.shape, std::vector<float>(a.data, a.data + a.size)});
  }
  WriteCheckpoint(path, ck);
}

namespace {

// Far above any preset (the paper's final grid is 300^3).
constexpr int kMaxCheckpointRes = 4096;

// Checks the grid's resolution and bounding box of the metadata before the grids are allocated
// from them (a damaged resolution would ask for GBs).
void CheckCheckpointGeometry(const std::string& path, const Checkpoint& ck, const Aabb& box,
                             const std::array<int, 3>& res) {
  for (int r : res) {
    if (r < 1 || r > kMaxCheckpointRes) {
      throw std::runtime_error(path + ": checkpoint grid resolution " + std::to_string(r) +
                               " outside [1, " + std::to_string(kMaxCheckpointRes) + "]");
    }
  }
  // Every plane is stored in the file, so its values bound the resolution: a damaged field
  // cannot make the grids larger than the data that fills them.
  size_t stored = 0;
  for (const CheckpointArray& a : ck.arrays) stored += a.data.size();
  for (int a = 0; a < 3; ++a) {
    if (size_t(res[a]) * size_t(res[(a + 1) % 3]) > stored) {
      throw std::runtime_error(path +
                               ": checkpoint grid resolution is larger than the values it stores");
    }
  }
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(box.min[a]) || !std::isfinite(box.max[a]) || !(box.min[a] < box.max[a])) {
      throw std::runtime_error(path + ": checkpoint bounding box is empty or not finite");
    }
  }
}

// Gives the model the checkpoint's shape (ranks, head width and kind, geometry, samples per ray).
// A run that pruned components or hidden units (trainer/train/component_prune.h) stored a smaller
// model than its options describe: the checkpoint's shape wins.
void ShapeModelAsCheckpoint(const std::string& path, const Checkpoint& ck, const nlohmann::json& j,
                            TensorfModel* model) {
  Aabb box;
  box.min = j.at("aabb_min").get<std::array<float, 3>>();
  box.max = j.at("aabb_max").get<std::array<float, 3>>();
  const std::array<int, 3> res = j.at("res").get<std::array<int, 3>>();
  CheckCheckpointGeometry(path, ck, box, res);
  TensorfConfig c = model->config();
  c.density_ranks = j.at("density_rank").get<std::array<int, 3>>();
  c.app_ranks = j.at("appearance_rank").get<std::array<int, 3>>();
  c.head.hidden = j.value("head", nlohmann::json::object()).value("hidden", c.head.hidden);
  c.head.num_products = c.app_ranks[0] + c.app_ranks[1] + c.app_ranks[2];
  if (c.density_ranks != model->config().density_ranks ||
      c.app_ranks != model->config().app_ranks || c.head.hidden != model->config().head.hidden) {
    for (int r : {c.density_ranks[0], c.density_ranks[1], c.density_ranks[2], c.app_ranks[0],
                  c.app_ranks[1], c.app_ranks[2], c.head.hidden}) {
      if (r < 1 || r > 1024) {
        throw std::runtime_error(path + ": checkpoint rank or head width " + std::to_string(r) +
                                 " outside [1, 1024]");
      }
    }
    *model = TensorfModel(c);
  }
  model->SetGeometry(box, res);
  // The sample spacing is the checkpoint's (--head auto may have doubled it), then its samples
  // per ray: a resumed run marches as the one it continues.
  const nlohmann::json render = j.value("render", nlohmann::json::object());
  model->SetStepRatio(render.value("step_ratio", model->config().step_ratio));
  model->set_n_samples(j.at("n_samples").get<int>());
  // --head auto may have switched the head during the run: the checkpoint's head wins too.
  const nlohmann::json head = j.value("head", nlohmann::json::object());
  model->SetHeadKind(ChoiceFromName<HeadKind>(head.value("kind", std::string(kHeadKindNames[0])),
                                              path + ": head"));
}

// Copies every parameter array of the model from the checkpoint: present, of the model's size,
// finite.
void LoadModelArrays(const std::string& path, const Checkpoint& ck, TensorfModel* model) {
  for (const NamedArray& a : model->NamedParameters()) {
    const CheckpointArray* src = ck.Find(a.name);
    if (!src) throw std::runtime_error(path + ": checkpoint lacks array '" + a.name + "'");
    if (src->data.size() != a.size) {
      throw std::runtime_error(path + ": array '" + a.name + "' has " +
                               std::to_string(src->data.size()) + " values, the model expects " +
                               std::to_string(a.size));
    }
    for (float x : src->data) {
      if (!std::isfinite(x))
        throw std::runtime_error(path + ": array '" + a.name + "' holds a non-finite value");
    }
    std::copy(src->data.begin(), src->data.end(), a.data);
  }
}

// The alpha mask, when the checkpoint has one. j is not const: its operator[] makes a missing key
// null, which get() then rejects with a json type error (const, a missing key is undefined).
void LoadAlphaMask(const std::string& path, const Checkpoint& ck, nlohmann::json& j,
                   TensorfModel* model) {
  if (!j.contains("mask_res")) return;
  const CheckpointArray* occ = ck.Find("alpha_mask");
  if (!occ) throw std::runtime_error(path + ": checkpoint lacks the alpha mask");
  Aabb box;
  box.min = j["mask_aabb_min"].get<std::array<float, 3>>();
  box.max = j["mask_aabb_max"].get<std::array<float, 3>>();
  const auto res = j["mask_res"].get<std::array<int, 3>>();
  if (occ->data.size() != size_t(res[0]) * res[1] * res[2]) {
    throw std::runtime_error(path + ": alpha mask size does not match its resolution");
  }
  std::vector<uint8_t> bits(occ->data.size());
  for (size_t i = 0; i < bits.size(); ++i) bits[i] = occ->data[i] > 0.5f;
  model->SetAlphaMask(AlphaMask(box, res, std::move(bits)));
}

// The rate state: the block shapes, and when rate training had started, the quantization steps,
// the entropy model and the rounding and RDOQ settings, each checked. j is not const, as for
// LoadAlphaMask.
void LoadRateState(const std::string& path, const Checkpoint& ck, nlohmann::json& j,
                   RateState* rate) {
  if (j.contains("plane_block") && j.contains("line_block")) {
    for (int a = 0; a < 3; ++a) {
      rate->config.plane_block[a] = j["plane_block"][a].get<int>();
      rate->config.line_block[a] = j["line_block"][a].get<int>();
    }
  }
  if (!j.value("rate_active", false)) return;
  const CheckpointArray* steps = ck.Find("rate.steps");
  const CheckpointArray* params = ck.Find("rate.entropy_model");
  if (!steps || !params) throw std::runtime_error(path + ": checkpoint lacks the rate state");
  for (float step : steps->data) {
    if (!(step > 0.f) || !std::isfinite(step)) {
      throw std::runtime_error(path + ": checkpoint holds a quantization step of " +
                               std::to_string(step) + " (steps are positive and finite)");
    }
  }
  rate->steps = steps->data;
  rate->entropy.Init(NumRateModels(2), 0);
  if (params->data.size() != rate->entropy.params().size()) {
    throw std::runtime_error(path + ": entropy model has the wrong number of parameters");
  }
  rate->entropy.params() = params->data;
  rate->adam.Reset(rate->entropy.params().size());
  rate->active = true;
  rate->checkpoint_lambda_e = j.value("lambda_e", 0.0f);
  rate->rate_control_last_bytes = j.value("rate_control_last_bytes", size_t(0));
  rate->rounding_offset = j.value("rounding_offset", 0.5f);
  if (!(rate->rounding_offset > 0.f && rate->rounding_offset <= 0.5f)) {
    throw std::runtime_error(path + ": checkpoint holds a rounding offset of " +
                             std::to_string(rate->rounding_offset) + " (expected (0, 0.5])");
  }
  rate->rdoq_lambda = j.value("rdoq_lambda", 0.0f);
  if (!(rate->rdoq_lambda >= 0.f && rate->rdoq_lambda <= encoder::kMaxRdoqLambda)) {
    throw std::runtime_error(path + ": checkpoint holds an RDOQ lambda of " +
                             std::to_string(rate->rdoq_lambda) + " (expected [0, " +
                             std::to_string(encoder::kMaxRdoqLambda) + "])");
  }
}

int LoadModelCheckpointOrThrow(const std::string& path, TensorfModel* model, RateState* rate,
                               Checkpoint* whole) {
  Checkpoint ck = ReadCheckpoint(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(ck.json);
    ShapeModelAsCheckpoint(path, ck, j, model);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": checkpoint metadata: " + e.what());
  }
  LoadModelArrays(path, ck, model);
  LoadAlphaMask(path, ck, j, model);
  if (rate) LoadRateState(path, ck, j, rate);
  const int iteration = j.at("iteration").get<int>();
  if (whole) *whole = std::move(ck);
  return iteration;
}

}  // namespace

int LoadModelCheckpoint(const std::string& path, TensorfModel* model, RateState* rate,
                        Checkpoint* whole) {
  try {
    return LoadModelCheckpointOrThrow(path, model, rate, whole);
  } catch (const std::invalid_argument& e) {  // the model's own checks do not know the file
    throw std::runtime_error(path + ": checkpoint does not describe a valid model: " + e.what());
  } catch (const std::length_error& e) {
    throw std::runtime_error(path + ": checkpoint does not describe a valid model: " + e.what());
  } catch (const std::bad_alloc&) {
    throw std::runtime_error(path +
                             ": checkpoint describes a model too large for this machine's memory");
  }
}

TensorfModel LoadModelFromCheckpoint(const std::string& path, RateState* rate) {
  TensorfConfig c;
  try {
    const nlohmann::json j = nlohmann::json::parse(ReadCheckpoint(path).json);
    c.density_ranks = j.at("density_rank").get<std::array<int, 3>>();
    c.app_ranks = j.at("appearance_rank").get<std::array<int, 3>>();
    // Checkpoints from before these fields were written hold the Blender defaults.
    const nlohmann::json render = j.value("render", nlohmann::json::object());
    c.near = render.value("near", c.near);
    c.far = render.value("far", c.far);
    c.white_background = render.value("white_background", c.white_background);
    c.density_shift = render.value("density_shift", c.density_shift);
    c.density_activation = ChoiceFromName<DensityActivation>(
        render.value("density_activation", std::string("softplus")), path + ": density_activation");
    c.distance_scale = render.value("distance_scale", c.distance_scale);
    c.step_ratio = render.value("step_ratio", c.step_ratio);
    c.weight_threshold = render.value("weight_threshold", c.weight_threshold);
    c.early_stop_transmittance = render.value("early_stop", c.early_stop_transmittance);
    const int scene_model = render.value("scene_model", 0);
    if (scene_model < 0 || scene_model >= kNumSceneModels) {
      throw std::runtime_error(path + ": checkpoint has unknown scene model " +
                               std::to_string(scene_model));
    }
    c.scene_model = static_cast<SceneModel>(scene_model);
    c.roi.min = render.value("roi_min", c.roi.min);
    c.roi.max = render.value("roi_max", c.roi.max);
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(c.roi.min[a]) || !std::isfinite(c.roi.max[a]) ||
          !(c.roi.min[a] < c.roi.max[a])) {
        throw std::runtime_error(path + ": checkpoint region of interest is empty or not finite");
      }
    }
    if (c.scene_model == SceneModel::kForward) {
      const std::vector<float> m = render.at("ndc_world_to_ref").get<std::vector<float>>();
      const std::vector<float> scale = render.at("ndc_scale").get<std::vector<float>>();
      if (m.size() != 12 || scale.size() != 2)
        throw std::runtime_error(path + ": checkpoint NDC frame has the wrong shape");
      std::copy(m.begin(), m.end(), c.ndc.world_to_ref);
      std::copy(scale.begin(), scale.end(), c.ndc.scale);
      c.ndc.near_plane = render.at("ndc_near_plane").get<float>();
      bool ok = std::all_of(m.begin(), m.end(), [](float v) { return std::isfinite(v); });
      for (float v : {c.ndc.scale[0], c.ndc.scale[1], c.ndc.near_plane})
        ok = ok && std::isfinite(v) && v > 0.f;
      if (!ok) throw std::runtime_error(path + ": checkpoint NDC frame is not finite and positive");
    }
    const nlohmann::json head = j.value("head", nlohmann::json::object());
    c.head.feature_dim = head.value("feature_dim", c.head.feature_dim);
    c.head.feature_pe_freqs = head.value("feature_pe_freqs", c.head.feature_pe_freqs);
    c.head.viewdir_pe_freqs = head.value("viewdir_pe_freqs", c.head.viewdir_pe_freqs);
    c.head.hidden = head.value("hidden", c.head.hidden);
    c.head.hidden_layers = head.value("hidden_layers", 2);  // checkpoints before 1.8 had two
    if (c.head.hidden_layers != 1 && c.head.hidden_layers != 2) {
      throw std::runtime_error(path + ": checkpoint head has " +
                               std::to_string(c.head.hidden_layers) + " hidden layers, not 1 or 2");
    }
    c.head.kind = ChoiceFromName<HeadKind>(head.value("kind", std::string(kHeadKindNames[0])),
                                           path + ": head");
    c.head.num_products = c.app_ranks[0] + c.app_ranks[1] + c.app_ranks[2];
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": checkpoint metadata: " + e.what());
  }
  TensorfModel model(c);
  LoadModelCheckpoint(path, &model, rate);
  return model;
}

CheckpointRunInfo ReadCheckpointRunInfo(const std::string& path) {
  const Checkpoint ck = ReadCheckpoint(path);
  CheckpointRunInfo info;
  try {
    const nlohmann::json j = nlohmann::json::parse(ck.json);
    info.iteration = j.value("iteration", 0);
    info.lambda_e = j.value("lambda_e", 0.0f);
    if (j.contains("config")) {
      info.config = TrainConfigFromJson(j["config"].dump(), path);
      info.has_config = true;
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": checkpoint metadata: " + e.what());
  }
  return info;
}

}  // namespace trainer
}  // namespace ecrf
