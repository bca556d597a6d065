// Which components of a trained run are worth their bits: a drop test per component.
//
// For every component r of mode m of the density or appearance grid (a plane channel and its
// line channel, the unit the stream can drop, SPEC.md 6.3), the test measures what the file
// saves without it (the encoder run again with the component zeroed: it is then dropped from the
// stream) and what the decoded model loses (its renders of training rays with the component's
// decoded plane and line channels zeroed). The training objective weighs both: a component is
// worth dropping when its MSE increase is below lambda_e times its bits, the trade the run itself
// was trained to make. All worthy drops are then applied together and measured as one file.
//
// Training optimises the components jointly with the rate term, but only by gradient: a whole
// component that costs more than it gives is a step no gradient takes. This is the "model only
// what a scene needs" test at the end of a run; `ecrf report components RUN` prints it.
#ifndef ECRF_TOOLS_REPORT_COMPONENT_DROP_H_
#define ECRF_TOOLS_REPORT_COMPONENT_DROP_H_

#include <cstddef>
#include <vector>

#include "encoder/scene_encoder.h"
#include "trainer/model/tensorf_model.h"

namespace ecrf {
namespace tools {

struct ComponentCost {
  int grid = 0;  // 0 density, 1 appearance
  int mode = 0;
  int component = 0;
  double dmse = 0.0;     // MSE increase of the decoded model without it
  long saved_bytes = 0;  // file bytes saved without it (the encoder's own count)
  bool drop = false;     // dmse < lambda_e * 8 * saved_bytes
};

struct ComponentReport {
  double lambda_e = 0.0;
  double mse = 0.0;  // decoded model on the rays
  size_t bytes = 0;  // the file as encoded
  std::vector<ComponentCost> components;
  int dropped = 0;
  size_t bytes_after = 0;  // the file with every component marked drop removed
  double mse_after = 0.0;  // its decoded model on the rays
  std::vector<uint8_t> file_after;
};

// Zeroes component r of mode m of grid g (its plane channel and its line channel).
void ZeroComponent(trainer::TensorfModel* model, int grid, int mode, int component);

// The drop test of every component of `model` coded with `options` (steps given), on n rays.
ComponentReport MeasureComponentCosts(const trainer::TensorfModel& model,
                                      const encoder::EncodeOptions& options, double lambda_e, int n,
                                      const float* origins, const float* dirs, const float* rgb);

int RunReportComponents(int argc, char** argv);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_REPORT_COMPONENT_DROP_H_
