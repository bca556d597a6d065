#include "tools/bench/scaling_model.h"

#include <gtest/gtest.h>

namespace ecrf {
namespace tools {
namespace {

std::vector<double> Amdahl(double t1, double s, const std::vector<int>& threads) {
  std::vector<double> t;
  for (int n : threads) t.push_back(t1 * (s + (1.0 - s) / n));
  return t;
}

TEST(ScalingModel, FitRecoversTheSerialFractionOfAmdahlTimes) {
  const std::vector<int> threads = {1, 2, 4, 8, 16};
  for (double s : {0.0, 0.05, 0.3, 1.0})
    EXPECT_NEAR(FitSerialFraction(threads, Amdahl(2.0, s, threads)), s, 1e-12) << s;
  // Two counts (the 2-core machine): the same serial fraction from one ratio.
  EXPECT_NEAR(FitSerialFraction({1, 2}, {1.0, 0.6}), 0.2, 1e-12);
}

TEST(ScalingModel, FitClampsAndRefusesWhatItCannotFit) {
  EXPECT_EQ(FitSerialFraction({1, 2}, {1.0, 0.4}), 0.0);   // superlinear: no negative fraction
  EXPECT_EQ(FitSerialFraction({1, 2}, {1.0, 1.3}), 1.0);   // slower with more threads
  EXPECT_EQ(FitSerialFraction({1}, {1.0}), -1.0);          // nothing above one thread
  EXPECT_EQ(FitSerialFraction({2, 4}, {1.0, 0.5}), -1.0);  // no one-thread time
}

TEST(ScalingModel, PredictionNamesWhatBoundsThePhase) {
  PhaseModel p;
  p.t1 = 1.0;
  p.serial = 0.01;
  Prediction a = PredictPhase(p, 8, 0, 0.0);
  EXPECT_NEAR(a.seconds, 0.01 + 0.99 / 8, 1e-12);
  EXPECT_EQ(a.bound, "parallel");
  // 200 threads: the serial 0.01 s is more than the 0.99 / 200 s parallel part.
  EXPECT_EQ(PredictPhase(p, 200, 0, 0.0).bound, "serial");
  // Six tasks cap the speedup at six.
  a = PredictPhase(p, 64, 6, 0.0);
  EXPECT_NEAR(a.seconds, 0.01 + 0.99 / 6, 1e-12);
  EXPECT_EQ(a.bound, "tasks");
  // 1 GB streamed at 20 GB/s takes 50 ms whatever the thread count.
  p.bytes = 1e9;
  a = PredictPhase(p, 64, 0, 20e9);
  EXPECT_NEAR(a.seconds, 0.05, 1e-12);
  EXPECT_EQ(a.bound, "memory");
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
