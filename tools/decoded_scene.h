// Host-side helpers around the embeddable decoder: read an .ecrf file, render dataset cameras
// from the decoded scene (with the trainer's ray generation, so lens distortion is honoured) and
// score the renders against ground truth.
#ifndef ECRF_TOOLS_DECODED_SCENE_H_
#define ECRF_TOOLS_DECODED_SCENE_H_

#include <memory>
#include <string>
#include <vector>

#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"
#include "trainer/data/dataset.h"
#include "trainer/data/image_io.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace tools {

struct LoadedScene {
  std::vector<uint8_t> bytes;
  std::unique_ptr<dec::SceneField> field;
  dec::SceneInfo info;  // info.metadata points into bytes
  double decode_seconds = 0.0;
};

// Throws std::runtime_error naming the file and the decoder's message.
// max_memory_bytes: DecodeOptions::max_memory_bytes (files from elsewhere keep the default
// budget; a stream ecrf just wrote itself may pass kUnlimitedMemory).
inline constexpr uint64_t kUnlimitedMemory = ~uint64_t{0};
// work_per_byte: DecodeOptions::work_per_byte.
LoadedScene DecodeSceneBytes(std::vector<uint8_t> bytes, const std::string& name,
                             dec::GridStorage storage = dec::GridStorage::kFloat32,
                             uint64_t max_memory_bytes = dec::kDefaultDecodeMemoryBudget,
                             uint64_t work_per_byte = dec::kDefaultDecodeWorkPerByte);
LoadedScene LoadSceneFile(const std::string& path,
                          dec::GridStorage storage = dec::GridStorage::kFloat32,
                          uint64_t max_memory_bytes = dec::kDefaultDecodeMemoryBudget,
                          uint64_t work_per_byte = dec::kDefaultDecodeWorkPerByte);

// RGB render of one camera; stats accumulate when given.
trainer::Image RenderDecoded(const dec::SceneField& scene, const trainer::Camera& camera,
                             const dec::RenderOptions& options, dec::RenderStats* stats = nullptr);

// Mean PSNR / SSIM over every stride-th test view (at most max_views; 0 = all).
// image_scale k > 1 renders at 1/k of the width and height (intrinsics scaled, distortion kept)
// and scores the bilinear upsampling to full size: what a viewer shows while it refines.
trainer::EvalResult EvaluateDecoded(const dec::SceneField& scene, const trainer::Dataset& test,
                                    int stride, int max_views, const dec::RenderOptions& options,
                                    bool keep_renders, int image_scale = 1,
                                    dec::RenderStats* stats = nullptr);

// A procedural scene's split as `ecrf train --scene NAME --seed seed` makes it (NAME builtin or
// capture; throws std::invalid_argument for others).
// Whether `name` is a procedural scene's (ecrf train --scene NAME), not a data directory.
bool IsProceduralScene(const std::string& name);
trainer::Dataset ProceduralDataset(const std::string& scene, const std::string& split,
                                   uint32_t seed);

// Bilinear resampling with pixel centres aligned (as OpenGL's texture filtering).
trainer::Image ResizeBilinear(const trainer::Image& image, int width, int height);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_DECODED_SCENE_H_
