// The camera warm-up pass: when the cameras are refined (--refine-cameras), a first, shorter
// training fits a field to the estimated cameras and refines them against it; the run then trains
// a fresh field from the refined cameras (and refines them further).
//
// Why: refinement settles where the field it refines against lets it. A field trained on cameras
// that are a few pixels off has blurred what they misplaced, and the blur holds the cameras back:
// more refinement rounds against the same field leave them where they are (about 0.8 % of the
// cameras' spread and 1.8 degrees on the procedural capture posed by COLMAP), while a fresh field
// trained from the refined cameras is sharper and moves them further
// (docs/photos-to-dataset.md, "Where the remaining gap comes from").
#ifndef ECRF_TRAINER_TRAIN_CAMERA_WARMUP_H_
#define ECRF_TRAINER_TRAIN_CAMERA_WARMUP_H_

#include <string>

#include "trainer/data/dataset.h"
#include "trainer/data/scene_fit.h"
#include "trainer/train/train_options.h"

namespace ecrf {
namespace trainer {

// The warm-up pass's length for this run: 0 when the cameras are not refined or
// camera_warmup_iters is 0; iters / 2 for -1 (auto).
int CameraWarmupIterations(const TrainOptions& options, const Dataset& train);

// The warm-up's directory inside the run directory ("" without one).
std::string CameraWarmupDir(const TrainOptions& options);

// The options the warm-up pass of `iters` iterations trains with (resume off; WarmUpCameras sets
// it from the checkpoint it finds): the run's, without rate objective, quantization, pruning or
// scoring, in CameraWarmupDir, and refining the cameras as often in iterations as the run does.
TrainOptions CameraWarmupOptions(const TrainOptions& options, int iters);

// Runs the warm-up pass when one is due (CameraWarmupIterations > 0): trains a field for that many
// iterations without the rate objective, refining the cameras as a run does, checkpointed in
// CameraWarmupDir (with options.resume it continues from there, or reloads a finished warm-up
// without training). Then sets train's cameras to the refined ones and test's to the held-out
// cameras carried along (the scored ones aligned to the warm-up's field), marks train's cameras
// warmed up, and returns true. Returns false, leaving both alone, when no warm-up is due, or when
// resuming a run whose checkpoint was trained without one.
bool WarmUpCameras(const TrainOptions& options, const SceneFit& fit, Dataset* train, Dataset* test);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_CAMERA_WARMUP_H_
