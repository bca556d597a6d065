// The training driver: data -> TensoRF VM model, with TensoRF's schedule (coarse-to-fine
// upsampling, alpha mask, bounding-box shrink, learning-rate decay), checkpoints, evaluation and
// metrics.json. The per-batch math lives in volume_render.h; this file only orchestrates.
#ifndef ECRF_TRAINER_TRAIN_TRAINER_H_
#define ECRF_TRAINER_TRAIN_TRAINER_H_

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "trainer/data/dataset.h"
#include "trainer/data/image_io.h"
#include "trainer/data/scene_fit.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/rate/coded_model.h"
#include "trainer/train/camera_refine.h"
#include "trainer/train/checkpoint.h"
#include "trainer/train/evaluate.h"
#include "trainer/train/head_choice.h"
#include "trainer/train/rate_state.h"
#include "trainer/train/train_options.h"
#include "trainer/train/train_schedule.h"  // RateStartIteration, QatStartIteration

namespace ecrf {
namespace trainer {

struct TrainResult {
  int iterations = 0;
  double train_seconds = 0.0;
  double final_train_psnr = 0.0;  // from the mean MSE of the last progress interval
  EvalResult test;
  std::vector<std::pair<double, double>> psnr_curve;  // (minutes, test PSNR) when --eval-every
  RateReport rate;             // bits per tensor of the rounded coefficients (when lambda_e > 0)
  float final_lambda_e = 0.f;  // options.lambda_e, or where rate control left it
  // Per training view and channel, the learnt exposure codes' log gains (empty when off).
  std::vector<float> exposure_log_gain;
  // With camera refinement (--refine-cameras): the refined training cameras, and the held-out
  // cameras aligned to the trained field, the ones to score the test views with (else empty).
  std::vector<Camera> train_cameras, test_cameras;
  std::vector<CameraRefineStats> camera_refinement;  // per round, the held-out alignment last
  HeadChoiceReport head_choice;  // --head auto: what it measured and chose (iteration -1: none)
};

// How a trained run is encoded: its block shapes and frozen steps, coefficient depth and MLP
// precision (metadata left empty).
encoder::EncodeOptions RunEncodeOptions(const TrainOptions& options, const RateState& rate);

// The datasets a run uses: the built-in procedural scene or a directory on disk.
Dataset LoadTrainingViews(const TrainOptions& options, const std::string& split);

// Model configuration for a dataset (its box, near/far, background), the options' ranks and the
// scene model of `fit` (unbounded: the grids span the contracted cube around fit.roi).
TensorfConfig ConfigFor(const TrainOptions& options, const Dataset& data, const SceneFit& fit);
// The transmittance at which training rays stop: options.early_stop, or for auto (< 0)
// kAutoEarlyStop in object scenes whose cameras are kept and 0 in the others.
float EarlyStopFor(const TrainOptions& options, const Dataset& data, const SceneFit& fit);
// The density activation of options.density_activation; auto: ReLU for the forward-facing model,
// softplus for the others.
DensityActivation DensityActivationFor(const TrainOptions& options, SceneModel model);
// The same with FitScene(options.scene_type, data).
TensorfConfig ConfigFor(const TrainOptions& options, const Dataset& data);

// Trains on `train`, evaluating on `test` at the end (and every options.eval_every iterations):
// a loop over the step and the scheduled events of train_events.h.
// Writes checkpoints and metrics.json into options.out_dir when it is not empty.
// `rate` receives the rate objective's state (steps, entropy model); it may be null.
TrainResult Train(const TrainOptions& options, const Dataset& train, const Dataset& test,
                  TensorfModel* model, RateState* rate = nullptr);

// Thrown by Train when options.stop_after (or stop_after_minutes) is reached, or a stop signal
// arrived (stop_signal.h): the checkpoint written at that iteration (if the run has an output
// directory) is the run's state.
class TrainingStopped : public std::runtime_error {
 public:
  explicit TrainingStopped(const std::string& what, int signal = 0)
      : std::runtime_error(what), signal_(signal) {}
  int signal() const { return signal_; }  // the signal that stopped the run; 0: an option

 private:
  int signal_;
};

// Checkpoint <-> model (+ training progress).
// `train_state` (optional, from SaveTrainState) goes into the same file: its arrays beside the
// model's, its JSON object under "train_state". `config` (optional): the run's resolved options
// (train_config.h), stored under "config" for `ecrf encode RUN` and `--resume`; `options` holds
// the live values (lambda_e under rate control).
void SaveModelCheckpoint(const std::string& path, TensorfModel& model, int iteration,
                         const TrainOptions& options, const RateState* rate = nullptr,
                         const Checkpoint* train_state = nullptr,
                         const TrainOptions* config = nullptr);
// The configuration a checkpoint was trained with (train_config.h), and its iteration and live
// lambda_e; false when it predates stored configurations. Throws on unreadable files.
struct CheckpointRunInfo {
  bool has_config = false;
  TrainOptions config;
  int iteration = 0;
  float lambda_e = 0.0f;  // where rate control left it
};
CheckpointRunInfo ReadCheckpointRunInfo(const std::string& path);
// A model of the checkpoint's own configuration (ranks, render parameters, head), loaded from it:
// what the encoder starts from. `rate` (optional) receives the rate state.
TensorfModel LoadModelFromCheckpoint(const std::string& path, RateState* rate = nullptr);
// Returns the iteration stored in the checkpoint. `rate` (optional) receives the rate state,
// `whole` (optional) the checkpoint as read (for LoadTrainState, without reading it twice).
int LoadModelCheckpoint(const std::string& path, TensorfModel* model, RateState* rate = nullptr,
                        Checkpoint* whole = nullptr);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_TRAINER_H_
