#include "tools/prepare/match_plan.h"

#include <algorithm>
#include <cmath>

namespace ecrf {
namespace tools {
namespace {

// Pairs of COLMAP's sequential matcher with quadratic overlap: frame i with i + 1, ..., i + overlap
// and with i + 2^k for k < overlap (an upper bound: the two sets share 1, 2, 4 and 8).
long long SequentialPairs(int frames) {
  long long pairs = 0;
  for (int i = 0; i < frames; ++i) {
    pairs += std::min(kSequentialOverlap, frames - 1 - i);
    for (int k = 0; k < kSequentialOverlap; ++k) {
      if (i + (1LL << k) < frames) ++pairs;
    }
  }
  return pairs;
}

double PairSeconds(int features) {
  const double f = double(features) / kMaxFeatures;
  return kPairSecondsAt8192 * f * f;
}

}  // namespace

MatchPlan PlanMatching(bool video, int frames, const std::string& matcher, int max_features) {
  MatchPlan plan;
  plan.matcher = matcher;
  if (matcher == "auto") {
    plan.matcher = video || frames > kExhaustiveMaxPhotos ? "sequential" : "exhaustive";
  }
  const long long n = std::max(frames, 0);
  plan.pairs = plan.matcher == "exhaustive" ? n * (n - 1) / 2 : SequentialPairs(frames);
  plan.features_auto = max_features <= 0;
  if (plan.features_auto) {
    // The most features (a multiple of 256) whose pairs fit the target.
    const double per_pair = kMatchSecondsTarget / double(std::max<long long>(plan.pairs, 1));
    const double f = kMaxFeatures * std::sqrt(per_pair / kPairSecondsAt8192);
    const int rounded = int(std::floor(std::min(f, double(kMaxFeatures)) / 256.0)) * 256;
    plan.max_features = std::clamp(rounded, kMinAutoFeatures, kMaxFeatures);
  } else {
    plan.max_features = max_features;
  }
  plan.predicted_seconds =
      double(plan.pairs) * PairSeconds(std::min(plan.max_features, kMaxFeatures));
  return plan;
}

}  // namespace tools
}  // namespace ecrf
