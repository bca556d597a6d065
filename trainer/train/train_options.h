// Training options and the named presets.
//
// Iteration milestones (upsampling, alpha-mask updates) are stated for a reference run length
// (30,000 iterations for `paper`) and scaled linearly when --iters changes: a milestone at
// iteration m of a reference run of R iterations happens at round(m * iters / R), so a shorter run
// keeps the same shape of schedule.
#ifndef ECRF_TRAINER_TRAIN_TRAIN_OPTIONS_H_
#define ECRF_TRAINER_TRAIN_TRAIN_OPTIONS_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ecrf {
namespace trainer {

// How many test views a run scores unless told otherwise: every K-th view with the smallest K
// that keeps at most this many (200 Synthetic-NeRF test views: every 10th, the views every
// compression figure of ecrf is measured on).
constexpr int kDefaultScoredTestViews = 20;

// The auto weight threshold of unbounded scenes (TrainOptions::weight_threshold; measured in
// docs/real-captures.md).
inline constexpr float kUnboundedWeightThreshold = 3e-3f;
// The auto plane total variation of unbounded scenes (TrainOptions::tv_weight_density/app).
inline constexpr float kUnboundedTvWeight = 1.f;

// The stretch of a run in which cameras are refined (shares of the iterations): from early coarse
// grids (a wide basin) to before the last steps, which then settle the field on final cameras.
inline constexpr float kRefineCamerasFrom = 0.2f, kRefineCamerasUntil = 0.8f;
// After a camera warm-up the cameras are close already: refining them from 20 % of the run, against
// a young field, first pulled them away again (1.35 degrees in the first round) and gained
// nothing; from half-way, half the rounds give the same held-out PSNR (docs/photos-to-dataset.md).
inline constexpr float kRefineCamerasFromWarmedUp = 0.5f;

struct TrainOptions {
  std::string preset = "fast";
  // The rate point the settings started from ("none": plain TensoRF, lambda_e 0; "low",
  // "medium", "high"; ApplyRatePoint), before flags adjusted them. Informational: the fields
  // below are what the run uses.
  std::string rate_point = "none";
  // Data.
  std::string data_dir;  // NeRF Blender or Instant-NGP/nerfstudio layout
  // "builtin" (Blender-like), "capture", "capture-sparse" or "forward" instead of data_dir;
  // "" = data_dir.
  std::string procedural_scene;
  // "auto" (from the camera layout, trainer/data/scene_fit.h), "object" or "unbounded".
  std::string scene_type = "auto";
  int downscale = 1;
  std::string out_dir;

  // Schedule.
  int iters = 30000;
  int reference_iters = 30000;  // the run length the milestones below are stated for
  int batch_rays = 4096;
  long voxels_init = 128L * 128 * 128;
  long voxels_final = 300L * 300 * 300;
  std::vector<int> upsample_iters = {2000, 3000, 4000, 5500, 7000};
  std::vector<int> alpha_mask_iters = {2000, 4000};
  // The alpha mask's grid points are this many grid cells apart (1: TensoRF's mask at the grid's
  // resolution). The mask is coded into the file (OCCU), so a coarser mask costs fewer bytes and
  // a thicker shell of evaluated samples; training and the file use the same mask.
  int mask_downscale = 1;
  float lr_grid = 0.02f;
  float lr_network = 1e-3f;
  float lr_decay_ratio = 0.1f;  // learning rates fall to this fraction over the run
  float l1_weight_initial = 8e-5f;
  float l1_weight_rest = 4e-5f;       // after the first alpha-mask update
  int max_samples_per_ray = 1000000;  // cap on TensoRF's n_samples (1e6 = no cap)
  // Weight of mip-NeRF 360's distortion loss (trainer/model/volume_render.h DistortionLoss): it
  // pulls each ray's weight into one short stretch, against floaters and fog between the views of
  // sparse captures. 0: off (TensoRF).
  float distortion_weight = 0.f;
  // TensoRF's TV_weight_density / TV_weight_app (VmGrid::PlaneTotalVariation), decayed as the
  // learning rates are (to lr_decay_ratio of it by the end) but never reset. TensoRF: 1.0 / 1.0 on
  // LLFF, 0 on Blender scenes. 0: off; < 0: auto, kUnboundedTvWeight for unbounded scenes (where
  // it gave the best held-out views in a smaller file, docs/real-captures.md), 0 for the others.
  float tv_weight_density = -1.f;
  float tv_weight_app = -1.f;
  // Per-image exposure codes (trainer/train/exposure_codes.h): "on", "off", or "auto" (on for
  // unbounded and forward-facing scenes, which come from cameras with auto exposure; off for
  // objects, whose renders share one exposure).
  std::string exposure_codes = "auto";
  float lr_exposure = 5e-3f;  // the codes' Adam learning rate (decays and resets with the others)
  // Photometric refinement of the training cameras against the field (trainer/train/
  // camera_refine.h): "on", "off", or "auto" (on for datasets whose poses were estimated, i.e.
  // Dataset::estimated_poses). When on, the held-out cameras follow the training ones and are
  // aligned to the trained field (6 degrees of freedom each) before they are scored, as evaluations
  // of NeRFs with learnt poses do.
  std::string refine_cameras = "auto";
  // The cameras are refined every this many iterations (0: iters / 50) from kRefineCamerasFrom
  // to kRefineCamerasUntil of the run: small steps interleaved with the field's, so that both
  // move together (a few large rounds left the field, blurred by the wrong cameras, to hold them
  // back between rounds).
  int refine_cameras_every = 0;
  // When the cameras are refined, a warm-up pass first trains a field for this many iterations
  // (no rate objective) and refines the cameras against it; the run then trains a fresh field
  // from those cameras (trainer/train/camera_warmup.h). -1: auto (iters / 2 when the cameras are
  // refined); 0: no warm-up.
  int camera_warmup_iters = -1;
  // The weight above which a sample is coloured by the MLP, in training and in the file's header
  // (SPEC 7.5). < 0: auto, kUnboundedWeightThreshold for unbounded scenes (whose hazy background
  // otherwise sends ~100 samples a ray through the MLP), TensoRF's 1e-4 for the others.
  float weight_threshold = -1.f;
  // Whether the low and medium rate points train a finer grid reached sooner (ApplyRatePoint).
  // Measured on `fast` only: on chair it gains 0.3-0.5 dB at equal size. `tiny` keeps its
  // schedule: on the built-in scene (1500 iterations) the finer grid lost 0.4 dB in the float
  // model and grew the file by 27%. `paper` is not measured (30k iterations).
  bool fine_grid_at_rate_points = false;

  // Model.
  int density_rank = 16;     // per mode
  int appearance_rank = 48;  // per mode
  int mlp_hidden = 128;      // width of the appearance MLP's two hidden layers (TensoRF: 128)

  // ECRF objective: loss = MSE + lambda_e * R + lambda_r * ||F(G)||^2, lambda_r = alpha * lambda_e.
  // R is the estimated size in bits of all coded grid coefficients (the same unit as the paper,
  // so lambda_e values carry over: 1e-10 means one bit is worth 1e-10 of per-channel MSE).
  float lambda_e = 0.0f;  // 0: plain TensoRF
  float alpha = 1.0f;
  int plane_block[3] = {16, 16, 16};  // channel x H x W
  int line_block[3] = {1, 8, 8};      // 1 x channel x L
  float rate_fraction = 0.1f;         // share of DCT blocks in each step's unbiased rate estimate
  float rate_start = 16000.0f / 30000.0f;  // share of the run after which the rate terms switch on
  float entropy_lr = 5e-3f;                // Adam rate of the entropy-model parameters
  int coef_bits = 8;                       // quantization depth the steps are chosen for
  // Each tensor's step is its largest block-DCT coefficient / the largest level (127 for 8
  // bits), times this factor, frozen when the rate terms switch on.
  float quant_step_scale = 1.0f;
  // The density tensors' steps are this factor times what quant_step_scale gives them (the
  // appearance tensors keep theirs): `ecrf report sensitivity` finds rendering more sensitive to
  // the density grid's quantization noise per coded level than to the appearance grid's.
  float density_step_factor = 1.0f;
  // Quantization-aware training (trainer/rate/quant_aware.h) from this share of the run on (>= 1:
  // never; < 0: from the start of the rate phase when the rate objective is on, else never),
  // the quantization error refreshed every qat_refresh iterations. The steps are frozen when it
  // starts (with lambda_e = 0 too). On by default: on chair it lifted the decoded file by
  // 0.12 dB at lambda_e 1e-10 and 0.37 dB at 5e-10 for the same size (docs/results.md).
  float qat_start = -1.0f;
  // The coefficient quantizer's rounding offset (encoder/coef_quantizer.h), in the encoder and in
  // quantization-aware training alike: 0.5 rounds to nearest.
  float rounding_offset = 0.5f;
  // > 0: the quantizer is RDOQ with this lambda (encoder/coef_rdoq.h), in training and encoding.
  float rdoq_lambda = 0.f;
  int qat_refresh = 1;
  // Rate-distortion pruning of whole components (trainer/train/component_prune.h) at these shares
  // of the rate phase (from its start to the end of the run; each in (0, 1), increasing; empty:
  // never; runs without a rate term never prune): at most
  // prune_share of each mode's components per test, judged on prune_rays training rays.
  std::vector<float> prune_at;
  float prune_share = 0.25f;
  int prune_rays = 8192;
  // How `ecrf train` codes the basis and MLP: > 0 integer levels (at most this many per row,
  // MLPW precision 2); 0 binary16. 127 cost no measurable PSNR on chair (docs/results.md) and
  // halves MLPW.
  int mlp_levels = 127;
  // > 0: lambda_e adapts during the rate phase so that the file lands at this size
  // (trainer/rate/train_rate_control.h), re-measured by encoding every rate_control_every
  // iterations; lambda_e, when given, is the starting value.
  size_t target_bytes = 0;
  int rate_control_every = 100;

  // Bookkeeping.
  uint32_t seed = 20211202;
  int checkpoint_every = 0;  // iterations; 0 = only the final checkpoint
  bool resume = false;
  // With resume: continue although the checkpoint's settings differ (train_config.h).
  bool accept_config_change = false;
  // Replace a run already in out_dir (its checkpoint, file and scores); without it (or resume)
  // such a directory is refused before any work.
  bool overwrite = false;
  // Leave after this many iterations as if killed (after the checkpoint due then, if any), by
  // throwing TrainingStopped: tests of exact resume, and a run split over sessions. 0 = never.
  int stop_after = 0;
  int test_view_stride = 0;  // score every k-th test view; 0: ScoredTestViewStride's default
  int max_test_views = 0;    // 0 = all
  // Also score the float model (before encoding) on the same views: the decoded file is always
  // scored; the float model costs about as much again (chair-400, 2 cores: 1.0 s a view, the
  // decoded file 0.9 s).
  bool score_float = false;
  // After a run without the rate term, fit an entropy model to its grids (300 steps) so that it
  // reports what its coefficients would cost (TrainResult::rate: the lambda_e = 0 point of a
  // sweep). Off for the camera warm-up, whose field is discarded. Not a flag, not in config.json.
  bool report_rate = true;
  int eval_downscale = 1;  // test views scored at 1/N of their size (area filter, cameras scaled)
  bool save_renders = false;
  int progress_every = 50;
  int eval_every =
      0;  // iterations between test evaluations for a PSNR-vs-time curve (0 = end only)

  // The built-in scene's size (train views; test views are an orbit of 1/4 as many).
  int builtin_size = 64;
  int builtin_views = 60;
  // The capture and forward scenes: frames of one hand-held loop or sweep, every 8th held out for
  // test.
  int capture_width = 120;
  int capture_height = 90;
  int capture_frames = 64;
};

// The stride of the scored test views: options.test_view_stride when set, else the smallest that
// keeps at most kDefaultScoredTestViews of `views`.
int ScoredTestViewStride(const TrainOptions& options, size_t views);

// "paper": the reference TensoRF VM-192 schedule. "fast": what a CPU user should run.
// "tiny": the built-in scene in CI. Throws std::invalid_argument for unknown names.
TrainOptions PresetOptions(const std::string& name);

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
  bool schedule = false;    // --final-grid, --upsample-at, --rate-start or --rate
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
inline const std::string& DataSource(const TrainOptions& o) {
  return o.procedural_scene.empty() ? o.data_dir : o.procedural_scene;
}

// --scene NAME: selects the procedural scene "builtin", "capture" or "forward" instead of --data.
// Throws std::invalid_argument for other names.
void SelectProceduralScene(const std::string& name, TrainOptions* options);

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
