// What `ecrf prepare` asks of COLMAP's matching, decided before any work: the matcher and the SIFT
// features per frame. Matching dominates a photo set's preparation (24.5 of 29 minutes for 50
// real full-HD photos, exhaustive, COLMAP's 8192 features: about 1.2 s a pair on 2 cores), and a
// pair's cost grows with the product of its two frames' feature counts, so the plan holds the
// pair count times the per-pair cost near a fixed time.
#ifndef ECRF_TOOLS_PREPARE_MATCH_PLAN_H_
#define ECRF_TOOLS_PREPARE_MATCH_PLAN_H_

#include <string>

namespace ecrf {
namespace tools {

// Photos up to this many are matched exhaustively (every pair: the most robust for an unordered
// set); more are matched sequentially, their names taken as capture order (phones and cameras
// number their files in time), each with its neighbours and the frames 2, 4, 8, ... away (COLMAP's
// quadratic overlap, which closes loops around an object).
inline constexpr int kExhaustiveMaxPhotos = 100;
// Sequential matching: neighbours on each side (COLMAP's SequentialMatching.overlap).
inline constexpr int kSequentialOverlap = 10;
// The matching time the automatic feature count aims at, and the measured cost of one pair at
// COLMAP's default 8192 features (2 cores, real photos) it scales from.
inline constexpr double kMatchSecondsTarget = 180.0;
inline constexpr double kPairSecondsAt8192 = 1.2;
inline constexpr int kMinAutoFeatures = 2048, kMaxFeatures = 8192;

struct MatchPlan {
  std::string matcher;   // "exhaustive" or "sequential"
  long long pairs = 0;   // image pairs COLMAP will match (sequential: an upper bound)
  int max_features = 0;  // SIFT features per frame
  bool features_auto = false;
  double predicted_seconds = 0.0;  // pairs x the per-pair cost at these features (real photos)
};

// matcher: "auto", "exhaustive" or "sequential"; max_features: 0 for automatic (the most, up to
// 8192, whose predicted matching time is within kMatchSecondsTarget, at least 2048).
MatchPlan PlanMatching(bool video, int frames, const std::string& matcher, int max_features);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_PREPARE_MATCH_PLAN_H_
