// A harder procedural phone capture, made to show the gap real captures show between the views
// a model was trained on and the views it was not: the still life in the room of the capture
// scene (capture_scene.h), filmed with the same lens, but
//  * with few frames (kSparseCaptureFrames, every 8th held out as usual),
//  * walked round unevenly: frames crowd on one side of the object and thin out on the other
//    (azimuth spacing varies 4:1 along the loop), so some held-out views look from where few
//    training views did,
//  * with auto exposure and auto white balance: each training frame is scaled by its own gain
//    (+-0.5 EV) and per-channel tint (+-6 %), clipped to [0, 1]; held-out frames keep the true
//    exposure, as a colour-calibrated test view would.
// The still life's specular highlights (still_life.h) make some of its colours view-dependent.
#ifndef ECRF_TRAINER_SCENES_SPARSE_CAPTURE_H_
#define ECRF_TRAINER_SCENES_SPARSE_CAPTURE_H_

#include <cstdint>
#include <string>

#include "trainer/data/dataset.h"

namespace ecrf::trainer {

inline constexpr int kSparseCaptureFrames = 24;

// The views of `split` ("train": 21 frames, "test" / "val": frames 0, 8, 16) of width x height,
// named capture-sparse/frame_NNN; the dataset's box, near and far as MakeCaptureScene's.
// Deterministic for given arguments. Throws std::runtime_error for a bad split or sizes.
Dataset MakeSparseCaptureScene(const std::string& split, int width, int height, uint32_t seed);

// The colour gain of training frame `frame` (the exposure times the tint of each channel); 1 for
// held-out frames.
void SparseCaptureGain(int frame, uint32_t seed, float gain[3]);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_SCENES_SPARSE_CAPTURE_H_
