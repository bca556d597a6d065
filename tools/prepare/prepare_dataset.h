// `ecrf prepare`: from a folder of photos or a video to a dataset the trainer reads.
//
// Frames (a video through Debian's ffmpeg) -> COLMAP structure from motion (feature extraction,
// matching, mapping; Debian's colmap, CPU only) -> the largest reconstructed model -> a
// transforms.json in the Instant-NGP layout (poses normalised as Instant-NGP's colmap2nerf does,
// OpenCV intrinsics with k1 k2 p1 p2 kept for the loader). Everything is written into a
// temporary folder beside the output, which is renamed into place only when the dataset is
// complete: a failed or interrupted run leaves nothing behind, and an existing output is never
// touched.
#ifndef ECRF_TOOLS_PREPARE_PREPARE_DATASET_H_
#define ECRF_TOOLS_PREPARE_PREPARE_DATASET_H_

#include <string>
#include <vector>

#include "tools/prepare/match_plan.h"
#include "trainer/data/named_choice.h"

namespace ecrf {
namespace tools {

// COLMAP's matching: every pair, neighbours in time, or auto (sequential for a video).
enum class ColmapMatcher { kAuto, kExhaustive, kSequential };

}  // namespace tools

template <>
struct trainer::ChoiceNames<tools::ColmapMatcher> {
  static constexpr const char* what = "matcher";
  static constexpr const char* names[] = {"auto", "exhaustive", "sequential"};
};

namespace tools {

struct PrepareOptions {
  std::string input;     // a folder of PNG / JPEG photos, or a video file
  std::string out_dir;   // must not exist (or be an empty folder)
  double fps = 2.0;      // video: frames extracted per second
  int max_frames = 300;  // video: at most this many frames
  int max_size = 0;  // video: longest side of the frames (0: the video's); photos: of SIFT's copy
  // exhaustive (every pair), sequential (neighbours in name order: video) or auto (sequential
  // for a video and for more than kExhaustiveMaxPhotos photos, exhaustive below: match_plan.h).
  std::string matcher = "auto";
  // COLMAP camera model, one shared by all frames: OPENCV (k1 k2 p1 p2), RADIAL, SIMPLE_RADIAL,
  // PINHOLE or SIMPLE_PINHOLE (the distortion models the trainer's loader reads).
  std::string camera_model = "OPENCV";
  // SIFT features per frame (0: automatic, the most up to COLMAP's 8192 whose matching is
  // predicted within about 3 minutes, at least 2048: match_plan.h); fewer match faster.
  int max_features = 0;
  int aabb_scale = 16;          // Instant-NGP's scene cube (the trainer fits its box inside)
  double min_registered = 0.5;  // fail when COLMAP poses a smaller share of the frames
  int threads = 0;              // 0: all cores
  std::string colmap = "colmap";
  std::string ffmpeg = "ffmpeg";
};

struct PrepareResult {
  int frames = 0;                         // images given to COLMAP
  int registered = 0;                     // images with a pose in transforms.json
  int models = 0;                         // reconstructions COLMAP made (the largest is kept)
  std::vector<std::string> unregistered;  // frames without a pose, by name
  MatchPlan plan;                         // the matcher and features COLMAP was given
};

// Throws std::runtime_error (or std::invalid_argument for bad options) with what failed, where
// and why: a missing program, an unreadable input, too few frames, a COLMAP step's exit status
// and the end of its log, or too few registered frames (naming some of them).
PrepareResult PrepareDataset(const PrepareOptions& options);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_PREPARE_PREPARE_DATASET_H_
