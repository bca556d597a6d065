// Rate control at encode time: the file for a size budget, from a trained scene alone.
//
// Every quantization step is scaled by one factor s (s > 1: coarser coefficients, fewer bytes;
// the relative step sizes the training chose are kept), and s is searched by bisection in log
// space for the finest quantization whose file fits the budget. Training with --lambda-e
// reaches a given size at a higher PSNR; this is what an encoder can do when the model is given.
#ifndef ECRF_ENCODER_ENCODE_RATE_CONTROL_H_
#define ECRF_ENCODER_ENCODE_RATE_CONTROL_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "encoder/scene_encoder.h"

namespace ecrf {
namespace encoder {

inline constexpr double kMaxStepScale = 64.0;

struct TargetSizeResult {
  std::vector<uint8_t> bytes;
  EncodeReport report;
  double step_scale = 1.0;  // the factor applied to every step
  int encodes = 0;          // files encoded during the search
};

// The largest file of at most target_bytes that scaling the steps reaches, within 1% of the
// target unless the steps hit a limit. A file smaller than the target at s = 1 is refined with
// s < 1 when the steps are coarser than the 8-bit peak step (a model trained with
// --quant-step-scale), never finer than FinestStepScale; at that limit the finest file is
// returned. Throws std::runtime_error naming the smallest reachable size when even
// s = kMaxStepScale does not fit.
TargetSizeResult EncodeToTargetSize(const SceneDescription& scene, const EncodeOptions& options,
                                    size_t target_bytes);

// The smallest factor s <= 1 that keeps every tensor's step at or above its 8-bit (or 16-bit)
// peak step, so that no coefficient clips: 1 when the steps are already the peak steps.
double FinestStepScale(const SceneDescription& scene, const EncodeOptions& options,
                       const std::vector<float>& base);

// "500KB", "1.2MB", "300000" (bytes; KB = 1000 bytes, MB = 10^6, also KiB / MiB). Throws
// std::invalid_argument naming the text.
size_t ParseByteSize(const std::string& text);

}  // namespace encoder
}  // namespace ecrf

#endif  // ECRF_ENCODER_ENCODE_RATE_CONTROL_H_
