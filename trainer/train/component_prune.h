// Rate–distortion pruning of whole components during training ("model only what a scene needs").
//
// A component (r of mode m of the density or appearance grid: a plane channel, its line channel
// and, for appearance, its basis column) is the unit the stream can leave out (SPEC.md 6.3). The
// rate term shrinks coefficients one gradient step at a time, but removing a component outright
// is a step no gradient takes: its coefficients keep costing bits while it gives less than they
// are worth. At each pruning point the trainer therefore tests every component in the units of
// its own loss, MSE + lambda_e * bits:
//   dmse: the rise in MSE on a batch of training rays when the component's products are zeroed
//         (the model as training renders it: quantized grids under QAT, each ray at its image's
//         exposure gain when the exposure codes are on); no other parameter adapts, so this
//         overstates what the component is worth;
//   bits: the rate estimate (the entropy model and frozen steps of the rate term, rounded
//         coefficients) of its mode's plane and line tensors with it, minus without it (the
//         component removed and the channel blocks packed again, as the encoder would code them).
// A component goes when dmse < lambda_e * bits, the least worth first, at most a share of each
// mode's components per test and never the last one, so that the rest can adapt before the next
// test. The grids, the head and the optimizers' moments shrink together and training goes on.
#ifndef ECRF_TRAINER_TRAIN_COMPONENT_PRUNE_H_
#define ECRF_TRAINER_TRAIN_COMPONENT_PRUNE_H_

#include <array>
#include <cstdint>
#include <vector>

#include "trainer/model/tensorf_model.h"
#include "trainer/train/rate_state.h"
#include "trainer/train/train_state.h"

namespace ecrf {
namespace trainer {

struct ComponentTest {
  int grid = 0;  // 0 density, 1 appearance
  int mode = 0;
  int component = 0;
  double dmse = 0.0;  // MSE rise without it
  double bits = 0.0;  // estimated bits saved without it
  bool drop = false;
};

struct PruneDecision {
  double mse = 0.0;  // of the model on the rays
  std::vector<ComponentTest> tests;
  // keep[g][m][r]: 1 for the components that stay.
  std::array<std::array<std::vector<uint8_t>, 3>, 2> keep;
  int dropped = 0;
};

// Tests every component of `model` (rendered as it is: apply QAT first to test the quantized
// grids) on n rays against rgb, with the rate state's steps and entropy model (rate.active).
// max_share in (0, 1]: the most components of one mode one test may drop. ray_gain (n x 3, may be
// null: all 1) are the rays' exposure gains, applied before the clamp as the training loss applies
// them: against the images' own exposures, a component would also be worth how well it fakes them.
PruneDecision TestComponents(const TensorfModel& model, const RateState& rate, double lambda_e,
                             int n, const float* origins, const float* dirs, const float* rgb,
                             double max_share, const float* ray_gain = nullptr);

// The head's width, chosen the same way. A hidden unit of either layer is tested by zeroing its
// row of weights and its bias (its output is then 0 after the ReLU, as if it were gone); its
// bits are the coded head's (MLPW, at the run's MLP levels; 16 bits a value for binary16). The
// stream has one width for both layers, so units go in pairs: the p-th least worth unit of the
// first layer with the p-th of the second, as many pairs as jointly give less MSE than lambda_e
// times the bits they save (at most max_share of the width, at least one unit stays).
struct HiddenDecision {
  double mse = 0.0;
  std::vector<double> dmse1, dmse2;   // per unit of the first and of the second hidden layer
  std::vector<uint8_t> keep1, keep2;  // 1 for the units that stay
  int dropped = 0;                    // units removed from each layer
  double bits = 0.0;                  // estimated bits the removal saves
};

HiddenDecision TestHiddenUnits(const TensorfModel& model, int mlp_levels, double lambda_e, int n,
                               const float* origins, const float* dirs, const float* rgb,
                               double max_share, const float* ray_gain = nullptr);
void PruneHidden(const HiddenDecision& decision, TensorfModel* model, Optimizers* opt);

// Removes the components the decision drops from the model (grids, head basis, config ranks) and
// the same entries of the optimizers' moments.
void PruneComponents(const PruneDecision& decision, TensorfModel* model, Optimizers* opt);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_COMPONENT_PRUNE_H_
