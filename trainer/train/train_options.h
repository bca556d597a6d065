// Training options (declared in train_fields.def), the named presets and rate points.
#ifndef ECRF_TRAINER_TRAIN_TRAIN_OPTIONS_H_
#define ECRF_TRAINER_TRAIN_TRAIN_OPTIONS_H_

#include <cstddef>
#include <cstdint>
#include <iterator>
#include <string>
#include <vector>

#include "decoder/render_work.h"  // kDeviceClasses, the --device-class budgets
#include "encoder/coef_rdoq.h"    // kMaxRdoqLambda, the --rdoq limit
#include "format/mlp_coder.h"     // HeadKind, the --head choice
#include "trainer/data/named_choice.h"
#include "trainer/data/scene_fit.h"
#include "trainer/train/train_field_info.h"

namespace ecrf {
namespace trainer {

// How many test views a run scores unless told otherwise: every K-th view with the smallest K
// that keeps at most this many (200 Synthetic-NeRF test views: every 10th, the views every
// compression figure of ecrf is measured on).
constexpr int kDefaultScoredTestViews = 20;

// The auto weight threshold of unbounded scenes (TrainOptions::weight_threshold; measured in
// docs/real-captures.md).
inline constexpr float kUnboundedWeightThreshold = 3e-3f;
// The auto early stop of training rays in object scenes whose cameras are kept
// (TrainOptions::early_stop): the transmittance at which the decoder's renders stop (SPEC.md 7.8).
inline constexpr float kAutoEarlyStop = 1e-4f;
// The auto plane total variation of unbounded and forward-facing scenes
// (TrainOptions::tv_weight_density/app): TensoRF's LLFF weight. Real captures' held-out views
// gain from it (docs/real-captures.md; LLFF flower, docs/results.md); objects get none.
inline constexpr float kCaptureTvWeight = 1.f;
// The weight of plane total variation a run uses: `weight` when given (>= 0), else auto.
inline float TvWeightFor(float weight, SceneModel scene) {
  if (weight >= 0.f) return weight;
  return scene == SceneModel::kObject ? 0.f : kCaptureTvWeight;
}

// The stretch of a run in which cameras are refined (shares of the iterations): from early coarse
// grids (a wide basin) to before the last steps, which then settle the field on final cameras.
inline constexpr float kRefineCamerasFrom = 0.2f, kRefineCamerasUntil = 0.8f;
// After a camera warm-up the cameras are close already: refining them from 20 % of the run, against
// a young field, first pulled them away again (1.35 degrees in the first round) and gained
// nothing; from half-way, half the rounds give the same held-out PSNR (docs/photos-to-dataset.md).
inline constexpr float kRefineCamerasFromWarmedUp = 0.5f;

template <>
struct ChoiceNames<HeadKind> {  // indexed by the MLPW head byte (format/mlp_coder.h)
  static constexpr const char* what = "head";
  static constexpr const char* const (&names)[kNumHeadKinds] = kHeadKindNames;
};
template <>
struct ChoiceNames<DensityActivation> {  // indexed by the HEAD byte (format/scene_header.h)
  static constexpr const char* what = "density activation";
  static constexpr const char* const (&names)[kNumDensityActivations] = kDensityActivationNames;
};
// --density-activation: one of the stream's, or auto (DensityActivationFor).
enum class DensityActivationChoice { kSoftplus, kRelu, kAuto };
template <>
struct ChoiceNames<DensityActivationChoice> {
  static constexpr const char* what = "density activation";
  static constexpr const char* names[] = {kDensityActivationNames[0], kDensityActivationNames[1],
                                          "auto"};
};
// --head: one of the stream's heads; sh, the deferred head with spherical-harmonics colour
// (HEAD hidden 0, SPEC.md 7.6.2); or auto (trainer/train/head_choice.h).
enum class HeadChoice { kMlp, kDeferred, kSh, kAuto };
template <>
struct ChoiceNames<HeadChoice> {
  static constexpr const char* what = "head";
  static constexpr const char* names[] = {kHeadKindNames[0], kHeadKindNames[1], kShHeadName,
                                          "auto"};
};
// --device-class: a render budget of decoder/render_work.h's table, or none.
enum class DeviceClassChoice { kNone, kDesktop, kLaptop, kPhone };
static_assert(std::size(dec::kDeviceClasses) == 3, "one choice per device class");
template <>
struct ChoiceNames<DeviceClassChoice> {
  static constexpr const char* what = "device class";
  static constexpr const char* names[] = {"none", dec::kDeviceClasses[0].name,
                                          dec::kDeviceClasses[1].name, dec::kDeviceClasses[2].name};
};

// The named presets (PresetOptions), rate points (ApplyRatePoint) and procedural scenes.
enum class Preset { kPaper, kFast, kTiny, kLong, kForward };
template <>
struct ChoiceNames<Preset> {
  static constexpr const char* what = "preset";
  static constexpr const char* names[] = {"paper", "fast", "tiny", "long", "forward"};
};
enum class RatePoint { kNone, kLow, kMedium, kHigh };
template <>
struct ChoiceNames<RatePoint> {
  static constexpr const char* what = "rate point";
  static constexpr const char* names[] = {"none", "low", "medium", "high"};
};
// kNone: the data come from data_dir.
enum class ProceduralScene { kNone, kBuiltin, kCapture, kCaptureSparse, kForward };
template <>
struct ChoiceNames<ProceduralScene> {
  static constexpr const char* what = "scene";
  static constexpr const char* names[] = {"", "builtin", "capture", "capture-sparse", "forward"};
};

// Every field, its default and its flag come from train_fields.def. A TrainOptions{} holds the
// paper schedule (the `paper` preset); PresetOptions gives the others.
struct TrainOptions {
#define ECRF_TRAIN_FIELD(type, name, info, ...) type name = __VA_ARGS__;
#include "trainer/train/train_fields.def"
#undef ECRF_TRAIN_FIELD
};
// The --test-stride help in train_fields.def names this number.
static_assert(kDefaultScoredTestViews == 20, "update --test-stride's help");

// The stride of the scored test views: options.test_view_stride when set, else the smallest that
// keeps at most kDefaultScoredTestViews of `views`.
int ScoredTestViewStride(const TrainOptions& options, size_t views);

// "paper": the reference TensoRF VM-192 schedule. "fast": what a CPU user should run.
// "tiny": the built-in scene in CI. "long": TensoRF's 30,000 iterations at a CPU's step cost,
// for the published tables at 800x800 (45 minutes on 2 cores). "forward": forward-facing
// captures (LLFF) in 45 minutes on 2 cores at 1008x756. The name form throws
// std::invalid_argument for unknown names.
TrainOptions PresetOptions(Preset preset);
TrainOptions PresetOptions(const std::string& name);

// What the default preset goes by: the dataset's cameras and background (tools/train_flags.cc).
enum class DataKind {
  kObjectWithGivenCameras,  // white background, poses not estimated (the Blender layout)
  kForwardFacing,           // every camera looks one way (CamerasFaceOneWay; LLFF)
  kOther,
};

// The preset a dataset trains with when the command line names none: `forward` for a
// forward-facing capture; `long` for an object dataset with given cameras whose training views
// hold more pixels than `fast`'s default run draws rays (FastRunRays(): 4,500 iterations of
// 4,096 rays), which would leave pixels unseen; `fast` otherwise. Chair at 400x400 (16.0 M
// pixels) stays `fast`; at 800x800 (64.0 M) `long` gives 33.59 dB at 0.5 MB in 45 min where
// `fast` gave 32.63 dB at 0.74 MB in 42 (docs/results.md). reason: one line for the run's log.
struct PresetChoice {
  Preset preset = Preset::kFast;
  std::string reason;
};
int64_t FastRunRays();
PresetChoice PresetForData(int64_t training_pixels, DataKind kind);

// The named rate points set lambda_e and the step scale (with quantization-aware training on):
//   "low"    lambda_e 2e-10, steps x4, 15 MLP levels, at most 32 appearance components, a
//            final grid (11/9)^3 times the preset's reached at 2/3 of its upsampling iterations:
//            chair-400 `fast` 240,086 B, 34.53 dB decoded (106.0x; at lambda_e 3e-10 206,819 B,
//            34.34 dB, 123.0x)
//   "medium" lambda_e 3e-11, steps x3, 31 MLP levels and the low point's grid schedule:
//            chair-400 `fast` 590,171 B, 35.34 dB decoded (43.1x at 0.00 dB against the
//            lambda = 0 float model)
//   "high"   lambda_e 2e-11, steps x1 (1,044,897 B, 35.19 dB before quantization-aware training)
//   "none"   plain TensoRF: lambda_e 0, steps x1 (the 8-bit peak steps), 127 MLP levels, the
//            preset's schedule: the float model every ratio is measured against
// (docs/user-guide.md gives the commands.) Throws std::invalid_argument for other names.
void ApplyRatePoint(RatePoint point, TrainOptions* options);
void ApplyRatePoint(const std::string& name, TrainOptions* options);

// The float32 size of the grids a run of these options ends with, before the box shrinks
// (voxels_final cubic voxels, every rank of both grids): what --target-size is measured against
// when it picks a step scale, before any data is read.
double NominalFloat32GridBytes(const TrainOptions& options);

// Which of the settings --target-size picks the user gave explicitly (those stay).
struct TargetSizeFlagsGiven {
  bool step_scale = false;  // --quant-step-scale or --rate
  bool mlp_levels = false;  // --mlp-levels or --rate
  bool ranks = false;       // --ranks or --rate
  bool schedule = false;    // --final-grid, --upsample-at or --rate
  bool rate_start = false;  // --rate-start (or --rate): kept when the schedule is --target-size's
  bool iters = false;       // --iters or --rate
};

// --target-size: the step scale of the nearest named rate point, by the target's share of
// NominalFloat32GridBytes; below 3% (chair-400 `fast`: 750 KB) also the low and medium points'
// grid schedule and iterations and the point's MLP levels, and below 1.6% (400 KB) at most 32
// appearance components (ApplyRatePoint). On chair-400 `fast` (docs/reports/chair_v2) steps x4 win
// below that share, x3 up to about 3%, and x2 above: never x1, so that encode-time rate control
// (encoder/encode_rate_control.h) can refine the steps when training ends below the target.
void ApplyTargetSizeDefaults(TrainOptions* options, const TargetSizeFlagsGiven& given);

// What a run's metrics record as its data: the procedural scene's name or the data directory.
inline std::string DataSource(const TrainOptions& o) {
  return o.procedural_scene == ProceduralScene::kNone ? o.data_dir : NameOf(o.procedural_scene);
}

// The iteration at which a reference milestone happens in a run of `iters` iterations.
int ScaleMilestone(int milestone, int iters, int reference_iters);

// Grid resolutions after each upsample: voxel counts spaced evenly in log space from
// voxels_init to voxels_final (TensoRF's N_voxel_list), turned into per-axis sizes for the box.
long ResolutionForVoxels(long voxels, const double aabb_min[3], const double aabb_max[3],
                         int res[3]);
std::vector<long> UpsampleVoxelCounts(const TrainOptions& options);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_TRAIN_OPTIONS_H_
