// A procedural stand-in for a phone capture: the still life of the builtin scene standing in
// a textured room, filmed hand-held with a distorting lens, in the Instant-NGP conventions.
#ifndef ECRF_TRAINER_SCENES_CAPTURE_SCENE_H_
#define ECRF_TRAINER_SCENES_CAPTURE_SCENE_H_

#include <cstdint>
#include <string>
#include <vector>

#include "trainer/data/dataset.h"
#include "trainer/scenes/procedural_math.h"

namespace ecrf::trainer {

// The room (z up, metres): 7.6 x 6.4, walls at x = +-3.8 and y = +-3.2, floor under the still
// life's slab, ceiling 3 m above the floor. Cameras stay inside it, so every ray ends on a surface.
inline constexpr double kCaptureRoomMin[3] = {-3.8, -3.2, -0.55};
inline constexpr double kCaptureRoomMax[3] = {3.8, 3.2, 2.45};
// Instant-NGP's aabb_scale for this capture: the smallest power of two whose cube holds the
// room (the cube is [-6.06, 6.06]^3, mostly outside the room: room for a fitted box to shrink).
inline constexpr double kCaptureAabbScale = 4.0;
// Horizontal field of view (62 degrees, a phone's main camera) and the lens.
inline constexpr double kCaptureFieldOfView = 1.0821041362364843;
inline constexpr double kCaptureK1 = -0.12;
inline constexpr double kCaptureK2 = 0.03;
// Principal point offset from the image centre, as fractions of width and height.
inline constexpr double kCaptureCxOffset = 0.031;
inline constexpr double kCaptureCyOffset = -0.022;
// Frames index % kCaptureTestEvery == 0 are held out, as Instant-NGP / LLFF loaders do.
inline constexpr int kCaptureTestEvery = 8;

// A capture of `num_frames` frames of width x height; returns the frames of `split`:
// "train" all but every 8th, "test" and "val" every 8th (frames 0, 8, 16, ...). Views are
// named capture/frame_NNN after their frame index.
// The camera path is a rough hand-held loop once around the still life: 2.17 to 2.83 m from its
// vertical axis, at z 0.5 to 1.3 (1.05 to 1.85 m above the floor), looking near the slab centre
// with a few degrees of roll, pitch and yaw jitter; all jitter and the loop's phase come from
// `seed`. Intrinsics: 62 degree horizontal field of view, square pixels, principal point off centre
// by (kCaptureCxOffset, kCaptureCyOffset) of the size, barrel distortion k1 -0.12, k2 0.03. Each
// pixel is one ray, exactly the one GenerateRay (and so RaySet) makes for it, so images and rays
// agree to the last bit; no supersampling, like a sensor with sharp optics. The dataset: aabb the
// cube Instant-NGP's aabb_scale 4 gives (about [-6.06, 6.06]^3), near and far from the cameras as
// for transforms.json, no white background. Deterministic for given arguments; 50 frames of 120x90
// render in about 0.15 s on 2 cores. Throws std::runtime_error for a bad split or sizes, or a split
// that would be empty.
Dataset MakeCaptureScene(const std::string& split, int width, int height, int num_frames,
                         uint32_t seed);

// A camera of the capture's phone (62 degree field of view, the principal point offset, the k1/k2
// lens) at `position` looking at `target`, then turned by roll, pitch and yaw (radians).
Camera CaptureCamera(const procedural::Vec3& position, const procedural::Vec3& target, double roll,
                     double pitch, double yaw, int width, int height);

// The colour the images show along a ray (unit `dir`): what a pixel of the scene is.
void CaptureSceneRadiance(const float origin[3], const float dir[3], float rgb[3]);

// How far (metres) the ray travels to the surface whose colour CaptureSceneRadiance returns:
// what LLFF-style depth bounds are measured from.
double CaptureSceneHitDistance(const float origin[3], const float dir[3]);

// The views of `split` of the still life in the room filmed by `cameras` (frame i is cameras[i]):
// every 8th frame (0, 8, ...) for "test" and "val", the others for "train", named
// SCENE/frame_NNN and rendered one ray per pixel as MakeCaptureScene's are. Shared so that the
// procedural captures split and render alike.
std::vector<View> RenderCaptureFrames(const char* scene, const std::vector<Camera>& cameras,
                                      const std::string& split);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_SCENES_CAPTURE_SCENE_H_
