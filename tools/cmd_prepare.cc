// `ecrf prepare PHOTOS_OR_VIDEO -o DATA`: posed images from a folder of photos or a video, through
// COLMAP (tools/prepare/prepare_dataset.h).
#include <cstdio>
#include <string>

#include "tools/cli.h"
#include "tools/commands.h"
#include "tools/prepare/colmap_model.h"
#include "tools/prepare/prepare_dataset.h"

namespace ecrf {
namespace tools {

int RunPrepare(int argc, char** argv) {
  PrepareOptions o;
  auto app = MakeCommand(
      "prepare",
      "posed images from photos or a video: frames (ffmpeg), structure from motion (COLMAP), "
      "a transforms.json that `ecrf train --data DATA` reads");
  app->add_option("INPUT", o.input, "a folder of PNG / JPEG photos, or a video file")
      ->type_name("PHOTOS|VIDEO")
      ->required();
  app->add_option("-o,--out", o.out_dir, "the dataset folder to write (must not exist)")
      ->type_name("DATA")
      ->required();
  app->add_option("--fps", o.fps, "video: frames per second to extract")->capture_default_str();
  app->add_option("--max-frames", o.max_frames, "video: at most this many frames")
      ->type_name("N")
      ->capture_default_str();
  app->add_option("--max-size", o.max_size,
                  "longest side in pixels: a video's frames are scaled to it; photos keep their "
                  "size and COLMAP's SIFT reads them scaled to it (0: as they are)")
      ->type_name("PX")
      ->capture_default_str();
  app->add_option("--matcher", o.matcher,
                  "COLMAP matching: exhaustive (every pair), sequential (neighbours in name "
                  "order, and frames 2, 4, 8, ... apart) or auto (sequential for a video and for "
                  "more than 100 photos, exhaustive below)")
      ->check(CLI::IsMember(trainer::TypedNames<ColmapMatcher>()))
      ->capture_default_str();
  app->add_option("--camera-model", o.camera_model,
                  "one camera for all frames (OPENCV: k1 k2 p1 p2)")
      ->check(CLI::IsMember(trainer::TypedNames<ColmapCameraModel>()))
      ->capture_default_str();
  app->add_option("--max-features", o.max_features,
                  "SIFT features per frame (0: automatic, the most up to 8192 whose matching "
                  "fits about 3 minutes, at least 2048); fewer match faster")
      ->type_name("N")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  app->add_option("--aabb-scale", o.aabb_scale,
                  "Instant-NGP scene cube, a power of two (the trainer fits its box inside)")
      ->check(CLI::IsMember({1, 2, 4, 8, 16, 32, 64, 128}))
      ->capture_default_str();
  app->add_option("--min-registered", o.min_registered,
                  "fail when COLMAP poses a smaller share of the frames")
      ->type_name("F")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app->add_option("--colmap", o.colmap, "the COLMAP program")->capture_default_str();
  app->add_option("--ffmpeg", o.ffmpeg, "the ffmpeg program")->capture_default_str();
  AddThreadsFlag(app.get(), &o.threads);
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  const PrepareResult r = PrepareDataset(o);
  std::printf("%s: %d of %d frames posed by COLMAP", o.out_dir.c_str(), r.registered, r.frames);
  if (r.models > 1) std::printf(" (the largest of %d reconstructions)", r.models);
  std::printf("\n");
  if (!r.unregistered.empty()) {
    std::printf("without a pose (left out of transforms.json):");
    for (const std::string& name : r.unregistered) std::printf(" %s", name.c_str());
    std::printf("\n");
  }
  std::printf("next: ecrf train --data %s -o RUN\n", o.out_dir.c_str());
  return 0;
}

}  // namespace tools
}  // namespace ecrf
