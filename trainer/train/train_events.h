// The training loop's pieces, in the way nerfstudio's trainer runs callbacks around each
// iteration: the step on a batch, and the events scheduled before and after it. Each event asks
// the run's TrainSchedule (train_schedule.h) whether it is due at iteration `it` (counted from
// 0) and does nothing when it is not. RunIteration calls them in their order, Train (trainer.h)
// runs the iterations and then FinishTraining. The order is part of the result: the events change
// what the step sees next (grids, optimizer moments, rays, lambda_e, cameras), so reordering them
// changes the trained bits.
#ifndef ECRF_TRAINER_TRAIN_TRAIN_EVENTS_H_
#define ECRF_TRAINER_TRAIN_TRAIN_EVENTS_H_

#include "trainer/train/train_session.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace trainer {

// The step (train_step.cc).
// The next batch of rays (and with exposure codes their gains); the gradients zeroed.
void DrawBatch(TrainSession& s);
// Rendering loss, regularizers (density L1, total variation, the rate terms) and the optimizers'
// step on the batch; throws when the loss or the head's gradient is not finite.
void OptimizeStep(TrainSession& s, int it);
// Every progress_every steps and after the last: a line with the loss of the interval, the
// grid, the samples, the speed and the estimated size; sets result.final_train_psnr.
void ReportProgress(TrainSession& s, int it);

// Before the step: the rate objective (rate_events.cc).
// From the rate phase on: starts --target-size's controller at an initial lambda_e, and switches
// the rate objective on (freezing the quantization steps for the final grid).
void StartRatePhase(TrainSession& s, int it);
// --target-size: encodes the model and moves lambda_e towards the target.
void ControlRate(TrainSession& s, int it);
// Quantization-aware training: the step sees the quantized grids (refreshed when due or when
// pruning changed their shapes); OptimizeStep puts the float grids back.
void QuantizeGrids(TrainSession& s, int it);

// After the step.
// --prune-at: removes the components and hidden units not worth their bits (rate_events.cc).
void PruneByRate(TrainSession& s, int it);
// --head auto, once the grid is final: the head by its predicted cost (head_choice.h).
void ChooseHeadIfAuto(TrainSession& s, int it);
// TensoRF's alpha-mask updates (grid_events.cc): the first shrinks the box to the occupied part
// (not for an unbounded scene), switches the density L1 weight to its later value and resets
// the optimizers; the second filters the training rays through the mask (an object scene only).
void UpdateAlphaMask(TrainSession& s, int it);
// When training ends (unless --keep-last-mask): the alpha mask from the trained density, on the
// last update's points (grid_events.cc).
void RefreshAlphaMask(TrainSession& s);
// TensoRF's coarse-to-fine upsampling to the next voxel count; resets the optimizers.
void UpsampleGrids(TrainSession& s, int it);
// --refine-cameras: one round of refining the training cameras against the field.
void RefineCameraRound(TrainSession& s, int it);
// --eval-every: a point of the held-out PSNR curve (its time is not training time)
// (run_events.cc).
void EvaluateTestCurve(TrainSession& s, int it);
// --checkpoint-every: the run's checkpoint, if the model is still finite.
void SaveRunCheckpoint(TrainSession& s, int it);
// --stop-after: throws TrainingStopped.
void StopIfAsked(TrainSession& s, int it);

// One iteration: the step and the events around it, in their order (trainer.cc).
void RunIteration(TrainSession& s, int it);

// After the last step (run_events.cc): the exposure and camera results, the final checkpoint,
// the rate report and (--score-float) the float model's score.
TrainResult FinishTraining(TrainSession& s);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_TRAIN_EVENTS_H_
