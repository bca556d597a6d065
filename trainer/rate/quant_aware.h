// Quantization-aware training of the feature grids.
//
// The decoder never sees the trained float grids G: it sees Q(G) = crop(IDCT(round(DCT(G) / s)
// * s)) per tensor, with the tensor's frozen step s (the encoder's quantizer, trainer/
// scene_encoder.h). Without training against Q the decoded file loses 0.2 - 0.8 dB at high
// lambda_e (docs/reports/chair). During quantization-aware steps the renderer samples Q(G) and
// the gradient it returns is applied to G unchanged (the straight-through estimator: dQ/dG taken
// as the identity), so G keeps learning while the loss is that of the decoded grids.
//
// The head (basis and MLP) is handled the same way when the run codes it as integer levels
// (MLPW precision 2): it is rendered as the decoder will reconstruct it.
//
// Cost: Q needs one forward and one inverse block DCT of every tensor. Refreshing it every k
// steps and reusing the quantization error E = Q(G) - G in between (rendering G + E) keeps the
// cost small; between refreshes G moves by a few Adam steps, far less than a step s.
#ifndef ECRF_TRAINER_RATE_QUANT_AWARE_H_
#define ECRF_TRAINER_RATE_QUANT_AWARE_H_

#include <vector>

#include "format/mlp_coder.h"
#include "trainer/model/tensorf_model.h"
#include "trainer/rate/rate_objective.h"

namespace ecrf {
namespace trainer {

// out = Q(grid) with steps[0..5] for tensors planes 0..2, lines 0..2 (the VmGrid flat order) and
// the encoder's rounding offset (encoder/coef_quantizer.h) or, with rdoq_lambda > 0, its RDOQ
// (encoder/coef_rdoq.h: the levels of the newest context set, unclipped); out has
// grid.params().size() values.
void ReconstructQuantizedGrid(const VmGrid& grid, const float* steps,
                              const encoder::RateConfig& config, std::vector<float>* out,
                              float rounding_offset = 0.5f, float rdoq_lambda = 0.f);

// The MLPW layout (format/mlp_coder.h) of a head: the trainer's flat parameter order is the
// stream's.
MlpLayout HeadMlpLayout(const AppearanceHeadConfig& head);

// out = the head parameters as MLPW precision 2 with at most max_level per row reconstructs them.
void ReconstructQuantizedHead(const TensorfModel& model, int max_level, std::vector<float>* out);

class QuantAwareModel {
 public:
  // Recomputes the quantization error of both grids; steps: 12 (density then appearance).
  // mlp_levels > 0: the head's too.
  void Refresh(const TensorfModel& model, const std::vector<float>& steps,
               const encoder::RateConfig& config, int mlp_levels = 0, float rounding_offset = 0.5f,
               float rdoq_lambda = 0.f);
  bool fresh_for(const TensorfModel& model) const;
  // Puts G + E into the model's grids (the float grids are kept aside); Restore() puts them back.
  // Between the two the model must not change shape.
  void Apply(TensorfModel* model);
  void Restore(TensorfModel* model);

 private:
  static std::vector<float>& Params(TensorfModel* model, int k);

  std::vector<float> error_[3];  // density, appearance, head: Q(G) - G at the last refresh
  std::vector<float> held_[3];   // the float parameters while Apply()ed
  bool applied_ = false;
};

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_RATE_QUANT_AWARE_H_
