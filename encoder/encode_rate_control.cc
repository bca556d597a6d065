#include "encoder/encode_rate_control.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "encoder/coded_tensors.h"

namespace ecrf {
namespace encoder {
namespace {

struct Encoded {
  std::vector<uint8_t> bytes;
  EncodeReport report;
};

Encoded EncodeWithScale(const SceneDescription& scene, EncodeOptions o,
                        const std::vector<float>& base, double scale, int* encodes) {
  for (size_t t = 0; t < base.size(); ++t) o.steps[t] = float(double(base[t]) * scale);
  Encoded e;
  e.bytes = EncodeScene(scene, o, &e.report);
  ++*encodes;
  return e;
}

}  // namespace

double FinestStepScale(const SceneDescription& scene, const EncodeOptions& options,
                       const std::vector<float>& base) {
  const double max_level = MaxCoefficientLevel(options.coef_bits);
  const std::vector<float> peaks = PeakCoefficients(scene, options.blocks);
  double finest = 0.0;
  for (size_t t = 0; t < base.size() && t < peaks.size(); ++t) {
    if (peaks[t] > 0.f && base[t] > 0.f)
      finest = std::max(finest, double(peaks[t]) / max_level / double(base[t]));
  }
  return std::min(1.0, finest > 0.0 ? finest : 1.0);
}

TargetSizeResult EncodeToTargetSize(const SceneDescription& scene, const EncodeOptions& options,
                                    size_t target_bytes) {
  EncodeOptions o = options;
  const std::vector<float> base =
      o.steps.empty() ? ChooseQuantSteps(scene, o.blocks, o.coef_bits) : o.steps;
  o.steps = base;
  TargetSizeResult r;
  auto close_enough = [&](const Encoded& e) {
    return e.bytes.size() >= size_t(0.99 * double(target_bytes));
  };
  auto done = [&](Encoded e, double scale) {
    r.bytes = std::move(e.bytes);
    r.report = e.report;
    r.step_scale = scale;
    return std::move(r);
  };
  Encoded fit = EncodeWithScale(scene, o, base, 1.0, &r.encodes);
  // Invariant of both searches: lo's file is too large, hi's fits. Sizes fall (almost)
  // monotonically with the scale; bisection in log space stops once the fitting file is within
  // 1% of the budget.
  double lo = 1.0, hi = 1.0;
  if (fit.bytes.size() <= target_bytes) {
    if (close_enough(fit)) return done(std::move(fit), 1.0);
    // Steps coarser than the 8-bit peak step (trained with --quant-step-scale) may be refined
    // down to it; nothing finer, or the largest coefficients would clip.
    const double finest = FinestStepScale(scene, o, base);
    if (!(finest < 1.0)) return done(std::move(fit), 1.0);
    Encoded fine = EncodeWithScale(scene, o, base, finest, &r.encodes);
    if (fine.bytes.size() <= target_bytes) return done(std::move(fine), finest);
    lo = finest;
  } else {
    Encoded coarsest = EncodeWithScale(scene, o, base, kMaxStepScale, &r.encodes);
    if (coarsest.bytes.size() > target_bytes) {
      char msg[256];
      std::snprintf(msg, sizeof(msg),
                    "cannot reach %zu bytes by coarser quantization: the smallest file is %zu "
                    "bytes (steps x%g), of "
                    "which the MLP takes %zu and the occupancy mask %zu",
                    target_bytes, coarsest.bytes.size(), kMaxStepScale, coarsest.report.mlp_bytes,
                    coarsest.report.occupancy_bytes);
      throw std::runtime_error(msg);
    }
    hi = kMaxStepScale;
    fit = std::move(coarsest);
  }
  for (int it = 0; it < 24 && !close_enough(fit); ++it) {
    const double mid = std::sqrt(lo * hi);
    Encoded e = EncodeWithScale(scene, o, base, mid, &r.encodes);
    if (e.bytes.size() <= target_bytes) {
      hi = mid;
      fit = std::move(e);
    } else {
      lo = mid;
    }
  }
  return done(std::move(fit), hi);
}

size_t ParseByteSize(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  // Units in any case ("500kb" is what people type): bytes are the only quantity here.
  std::string unit = end ? std::string(end) : "";
  for (char& ch : unit) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  double mult = 0;
  if (unit.empty() || unit == "b")
    mult = 1;
  else if (unit == "kb" || unit == "k")
    mult = 1e3;
  else if (unit == "mb" || unit == "m")
    mult = 1e6;
  else if (unit == "kib")
    mult = 1024;
  else if (unit == "mib")
    mult = 1024.0 * 1024;
  if (mult == 0 || !(v > 0) || !std::isfinite(v) || v * mult > 1e12) {
    throw std::invalid_argument("'" + text + "' is not a size (e.g. 500KB, 1.2MB, 300000B)");
  }
  return size_t(std::llround(v * mult));
}

}  // namespace encoder
}  // namespace ecrf
