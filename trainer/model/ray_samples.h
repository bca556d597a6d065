// The samples of one ray as the trainer's renderer evaluates them (volume_render.h's TrainStep,
// RenderRays and TraceRay share this code path): the candidate points inside the box and the
// alpha mask (object, unbounded and forward-facing scene models, SPEC.md 7.2), then their
// densities, alphas and transmittances, with the grid prefetched a few samples ahead. Internal to
// trainer/model; volume_render.cc batches it over rays.
#ifndef ECRF_TRAINER_MODEL_RAY_SAMPLES_H_
#define ECRF_TRAINER_MODEL_RAY_SAMPLES_H_

#include <array>
#include <cstdint>
#include <vector>

#include "decoder/grid_point.h"
#include "format/ndc_frame.h"
#include "trainer/model/tensorf_model.h"

namespace ecrf {
namespace trainer {
namespace march {

constexpr int kPrefetchDistance = 4;  // samples ahead

// The per-ray hash of RayJitter and of TrainStep's random background.
inline uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// One evaluated sample of a ray (inside the aabb and the alpha mask).
struct SampleRec {
  GridPoint gp;  // kept so the gather and scatter passes need not locate the sample again
  float t;
  float s;  // distance along the ray in sampling units (steps of `step`), for the distortion loss
  float dscale;  // dist * distance_scale of this sample's interval
  float feat;    // density feature + shift; after the composite pass: dL/d(feature)
  float alpha;
  float trans;  // transmittance before this sample
  int app;      // row in the batch's appearance matrix, or -1
};

// A sample inside the aabb and the mask, before its density is known.
struct Candidate {
  float t;
  float s;  // as SampleRec::s
  float dscale;
  GridPoint gp;
};

// What marching needs of a model, read once per batch.
struct MarchParams {
  Aabb box;
  std::array<float, 3> inv_size;
  std::array<int, 3> res;
  DensityActivation activation;
  float near, far, step, dscale, shift, weight_threshold, early_stop;
  int n_samples;
  const AlphaMask* mask;
  const VmGrid* density;
  // Unbounded scene model (SPEC.md 7.2.1): box is the contracted cube, these normalise world
  // points by the region of interest.
  bool unbounded;
  float distance_scale;
  float roi_min[3], roi_scale[3];
  // Forward-facing scene model (SPEC.md 7.2.2): box is in the NDC of this frame.
  bool forward;
  NdcFrame ndc;
};

// Throws std::runtime_error for a model without samples per ray or grid.
MarchParams MakeMarchParams(const TensorfModel& model);

// Marches one ray: appends its evaluated samples to buf (their count to *count), returns the
// number of appearance samples (their `app` field holds the local index 0..k-1 until offset by
// the caller). cand is scratch.
int MarchRay(const MarchParams& p, const float* o, const float* d, float jitter,
             std::vector<Candidate>& cand, std::vector<SampleRec>& buf, int* count);

}  // namespace march
}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_MODEL_RAY_SAMPLES_H_
