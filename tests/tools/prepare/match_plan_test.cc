// The matching plan of `ecrf prepare` (tools/prepare/match_plan.h): which matcher and how many
// SIFT features a frame, before COLMAP runs.
#include "tools/prepare/match_plan.h"

#include <gtest/gtest.h>

namespace ecrf {
namespace tools {
namespace {

TEST(MatchPlan, AutoMatchesSmallPhotoSetsExhaustivelyAndVideosAndLargeSetsSequentially) {
  EXPECT_EQ(PlanMatching(false, 50, "auto", 0).matcher, "exhaustive");
  EXPECT_EQ(PlanMatching(false, kExhaustiveMaxPhotos, "auto", 0).matcher, "exhaustive");
  EXPECT_EQ(PlanMatching(false, kExhaustiveMaxPhotos + 1, "auto", 0).matcher, "sequential");
  EXPECT_EQ(PlanMatching(true, 20, "auto", 0).matcher, "sequential");
  // A named matcher is kept, whatever the input.
  EXPECT_EQ(PlanMatching(true, 20, "exhaustive", 0).matcher, "exhaustive");
  EXPECT_EQ(PlanMatching(false, 20, "sequential", 0).matcher, "sequential");
}

TEST(MatchPlan, PairsAreEveryPairOrTheSequentialNeighbours) {
  EXPECT_EQ(PlanMatching(false, 50, "exhaustive", 0).pairs, 50 * 49 / 2);
  EXPECT_EQ(PlanMatching(false, 3, "exhaustive", 0).pairs, 3);
  // Three frames in sequence: 0-1, 0-2, 1-2 as neighbours, plus 0+1, 0+2, 1+1 by the quadratic
  // overlap (counted again: an upper bound).
  EXPECT_EQ(PlanMatching(true, 3, "sequential", 0).pairs, 6);
  // Many frames: each has at most 10 neighbours ahead and 10 quadratic partners.
  const MatchPlan many = PlanMatching(false, 500, "auto", 0);
  EXPECT_GT(many.pairs, 500 * 10);
  EXPECT_LE(many.pairs, 500 * 20);
}

TEST(MatchPlan, AutomaticFeaturesHoldTheMatchingTimeNearTheTarget) {
  // Few pairs: COLMAP's full 8192.
  const MatchPlan few = PlanMatching(false, 10, "auto", 0);
  EXPECT_TRUE(few.features_auto);
  EXPECT_EQ(few.max_features, kMaxFeatures);
  // 50 photos, 1225 pairs: fewer features, the predicted time within the target, and the most
  // features that are (256 more would pass it).
  const MatchPlan fifty = PlanMatching(false, 50, "auto", 0);
  EXPECT_LT(fifty.max_features, kMaxFeatures);
  EXPECT_EQ(fifty.max_features % 256, 0);
  EXPECT_LE(fifty.predicted_seconds, kMatchSecondsTarget);
  const double f = (fifty.max_features + 256.0) / kMaxFeatures;
  EXPECT_GT(double(fifty.pairs) * kPairSecondsAt8192 * f * f, kMatchSecondsTarget);
  // So many pairs that the target cannot be met: the floor, and the prediction says so.
  const MatchPlan big = PlanMatching(false, 100, "exhaustive", 0);
  EXPECT_EQ(big.max_features, kMinAutoFeatures);
  EXPECT_GT(big.predicted_seconds, kMatchSecondsTarget);
  // A count the user gives is kept.
  const MatchPlan given = PlanMatching(false, 50, "auto", 6000);
  EXPECT_FALSE(given.features_auto);
  EXPECT_EQ(given.max_features, 6000);
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
