#include "trainer/train/trainer.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "decoder/contraction.h"
#include "trainer/scenes/builtin_scene.h"
#include "trainer/scenes/capture_scene.h"
#include "trainer/scenes/forward_scene.h"
#include "trainer/scenes/sparse_capture.h"
#include "trainer/train/train_events.h"

namespace ecrf {
namespace trainer {

Dataset LoadTrainingViews(const TrainOptions& o, const std::string& split) {
  switch (o.procedural_scene) {
    case ProceduralScene::kCapture:
      return MakeCaptureScene(split, o.capture_width, o.capture_height, o.capture_frames, o.seed);
    case ProceduralScene::kCaptureSparse:
      return MakeSparseCaptureScene(split, o.capture_width, o.capture_height, o.seed);
    case ProceduralScene::kForward:
      return MakeForwardScene(split, o.capture_width, o.capture_height, o.capture_frames, o.seed);
    case ProceduralScene::kBuiltin: {
      const int views = split == "train" ? o.builtin_views : std::max(4, o.builtin_views / 4);
      return MakeBuiltinScene(split, o.builtin_size, o.builtin_size, views, o.seed);
    }
    case ProceduralScene::kNone:
      break;
  }
  if (o.data_dir.empty())
    throw std::invalid_argument("no data: give --data DIR or --scene builtin");
  return LoadDataset(o.data_dir, split, o.downscale);
}

TensorfConfig ConfigFor(const TrainOptions& o, const Dataset& data) {
  return ConfigFor(o, data, FitScene(o.scene_type, data));
}

float EarlyStopFor(const TrainOptions& o, const Dataset& data, const SceneFit& fit) {
  if (o.early_stop >= 0.f) return o.early_stop;
  return fit.model == SceneModel::kObject && !RefineCamerasOn(o, data) ? kAutoEarlyStop : 0.f;
}

DensityActivation DensityActivationFor(const TrainOptions& o, SceneModel model) {
  switch (o.density_activation) {
    case DensityActivationChoice::kSoftplus:
      return DensityActivation::kSoftplus;
    case DensityActivationChoice::kRelu:
      return DensityActivation::kRelu;
    case DensityActivationChoice::kAuto:
      break;
  }
  return model == SceneModel::kForward ? DensityActivation::kRelu : DensityActivation::kSoftplus;
}

TensorfConfig ConfigFor(const TrainOptions& o, const Dataset& data, const SceneFit& fit) {
  TensorfConfig c;
  c.density_ranks = {o.density_rank, o.density_rank, o.density_rank};
  c.app_ranks = {o.appearance_rank, o.appearance_rank, o.appearance_rank};
  c.head.num_products = 3 * o.appearance_rank;
  c.head.hidden = o.mlp_hidden;
  c.head.hidden_layers = o.mlp_layers;
  c.head.feature_pe_freqs = o.feature_pe_freqs;
  c.head.viewdir_pe_freqs = o.viewdir_pe_freqs;
  c.step_ratio = o.step_ratio;
  // auto starts with the per-sample head and may switch once the grid is final (head_choice.h).
  c.head.kind = o.head == HeadChoice::kDeferred || o.head == HeadChoice::kSh ? HeadKind::kDeferred
                                                                             : HeadKind::kPerSample;
  if (o.head == HeadChoice::kSh) c.head = ShHeadConfig(c.head, o.sh_degree);
  c.near = float(data.near);
  c.far = float(data.far);
  c.white_background = data.white_background;
  c.max_samples = o.max_samples_per_ray;
  c.early_stop_transmittance = EarlyStopFor(o, data, fit);
  for (int a = 0; a < 3; ++a) {
    c.aabb.min[a] = float(data.scene_aabb[0][a]);
    c.aabb.max[a] = float(data.scene_aabb[1][a]);
  }
  c.scene_model = fit.model;
  c.density_activation = DensityActivationFor(o, fit.model);
  if (c.density_activation == DensityActivation::kRelu) c.density_shift = 0.f;  // TensoRF's LLFF
  if (fit.model == SceneModel::kForward) {
    c.ndc = fit.ndc;
    c.aabb = fit.roi;  // the NDC box
    c.near = 0.f;      // rays start on the near plane (NDC z = -1)
    c.far = 10.f;  // past the far side of any NDC box of cameras narrower than about 160 degrees
  }
  if (o.weight_threshold >= 0.f) {
    c.weight_threshold = o.weight_threshold;
  } else if (fit.model == SceneModel::kUnbounded) {
    c.weight_threshold = kUnboundedWeightThreshold;
  }
  if (fit.model == SceneModel::kUnbounded) {
    c.roi = fit.roi;
    for (int a = 0; a < 3; ++a) {
      c.aabb.min[a] = -kContractedExtent;
      c.aabb.max[a] = kContractedExtent;
    }
  }
  return c;
}

encoder::EncodeOptions RunEncodeOptions(const TrainOptions& o, const RateState& rate) {
  encoder::EncodeOptions eo;
  eo.blocks = rate.config;
  eo.steps = rate.steps;
  eo.coef_bits = o.coef_bits;
  eo.mlp_max_level = o.mlp_levels;
  eo.rounding_offset = o.rounding_offset;
  eo.rdoq_lambda = o.rdoq_lambda;
  return eo;
}

void RunIteration(TrainSession& s, int it) {
  DrawBatch(s);
  ChooseHeadIfAuto(s, it);
  StartRatePhase(s, it);
  ControlRate(s, it);
  QuantizeGrids(s, it);
  OptimizeStep(s, it);
  ReportProgress(s, it);
  PruneByRate(s, it);
  UpdateAlphaMask(s, it);  // TensoRF's order: the alpha mask (shrink, ray filtering) first,
  UpsampleGrids(s, it);    // then upsampling
  RefineCameraRound(s, it);
  EvaluateTestCurve(s, it);
  SaveRunCheckpoint(s, it);
  StopIfAsked(s, it);
}

TrainResult Train(const TrainOptions& o, const Dataset& train, const Dataset& test,
                  TensorfModel* model, RateState* rate_out) {
  RateState local_rate;
  RateState* rate = rate_out ? rate_out : &local_rate;
  TrainSession s(o, train, test, model, rate, StartModel(o, train, model, rate));
  for (int it = s.first_iter; it < o.iters; ++it) RunIteration(s, it);
  return FinishTraining(s);
}

}  // namespace trainer
}  // namespace ecrf
