// A procedural stand-in for an LLFF "real forward-facing" capture: the capture scene's still
// life in its room, photographed from in front by a hand sweeping a phone over a small patch.
#ifndef ECRF_TRAINER_SCENES_FORWARD_SCENE_H_
#define ECRF_TRAINER_SCENES_FORWARD_SCENE_H_

#include <cstdint>
#include <string>

#include "trainer/data/dataset.h"

namespace ecrf::trainer {

// The camera centres tile a patch this wide and tall (metres) facing the still life, its centre
// kForwardDistance from kForwardTarget and kForwardElevation above it, on the -y side: the
// cameras look towards +y, at the window wall 3.2 m behind the still life.
inline constexpr double kForwardPatchWidth = 0.64;
inline constexpr double kForwardPatchHeight = 0.36;
inline constexpr double kForwardDistance = 2.5;
inline constexpr double kForwardElevation = 0.2617993877991494;  // 15 degrees
inline constexpr double kForwardTarget[3] = {0.0, 0.0, 0.0};
// LLFF's bounds convention: the near plane is this share of the nearest surface depth.
inline constexpr double kForwardNearShare = 0.9;

// A forward-facing capture of `num_frames` frames of width x height; returns the frames of
// `split`: "train" all but every 8th, "test" and "val" every 8th (frames 0, 8, 16, ...), named
// forward/frame_NNN after their frame index.
// The rig: the frames fill the patch row by row from the top, left to right then back, as a
// person sweeps a phone (rows as near round(sqrt(frames x 0.36 / 0.64)) as the frame count
// allows; each row's frames spread evenly over its width), each centre jittered by up to 0.3 of
// its cell and 3 cm towards or away from the still life. Every camera looks at a point within
// 5 cm of kForwardTarget with up to 2 degrees of roll and 1.5 of pitch and yaw; all jitter comes
// from `seed`. The viewing directions stay within about 10 degrees of their mean.
// Intrinsics: the capture scene's phone (62 degree horizontal field of view, principal point off
// centre by (kCaptureCxOffset, kCaptureCyOffset) of the size) without lens distortion, as
// LLFF's images are undistorted. One ray per pixel, exactly GenerateRay's.
// The dataset: aabb the room (kCaptureRoomMin/Max), no white background, and LLFF's bounds:
// far is the largest depth (distance along the viewing axis, -z in camera coordinates) at which
// a pixel ray of any frame of the capture, whatever the split, meets a surface, and near
// kForwardNearShare of the smallest.
// Deterministic for given arguments. Throws std::runtime_error for a bad split or sizes, or a
// split that would be empty.
Dataset MakeForwardScene(const std::string& split, int width, int height, int num_frames,
                         uint32_t seed);

}  // namespace ecrf::trainer

#endif  // ECRF_TRAINER_SCENES_FORWARD_SCENE_H_
