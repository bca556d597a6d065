// Rate control during training: the starting lambda_e reproduces the measured chair curve, and
// the multiplicative update settles a delayed, nonlinear size response at the target.
#include "trainer/rate/train_rate_control.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ecrf {
namespace trainer {
namespace {

TEST(TrainRateControl, InitialLambdaFollowsTheChairCurve) {
  // docs/reports/chair: lambda_e 1e-10 -> 571,390 bytes of a 25,438,668-byte float32 model.
  EXPECT_NEAR(std::log10(InitialLambdaForSize(571390, 25438668)), -10.0, 0.02);
  // Smaller files need larger lambdas; the ends are clamped.
  EXPECT_GT(InitialLambdaForSize(283281, 25438668), 4e-10f);
  EXPECT_LT(InitialLambdaForSize(283281, 25438668), 6e-10f);
  EXPECT_FLOAT_EQ(InitialLambdaForSize(1, 25438668), 1e-8f);
  EXPECT_FLOAT_EQ(InitialLambdaForSize(25438668, 25438668), 1e-12f);
  EXPECT_THROW(InitialLambdaForSize(0, 10), std::invalid_argument);
}

// A plant like training: the size the grids settle at is c * lambda^-0.45 (c unknown to the
// controller, off by 3x from the chair fit), and the grids move only 30% of the way there
// between two updates.
TEST(TrainRateControl, SettlesADelayedResponseAtTheTarget) {
  for (double c_factor : {1.0 / 3.0, 3.0}) {
    const size_t target = 400000;
    const double c = c_factor * 571390.0 * std::pow(1e-10, 0.45);
    LambdaController control(target, InitialLambdaForSize(target, 25438668));
    double size = c * std::pow(control.lambda_e(), -0.45);
    for (int update = 0; update < 14; ++update) {
      const double settled = c * std::pow(control.lambda_e(), -0.45);
      size += 0.3 * (settled - size);
      control.Update(size_t(size));
    }
    EXPECT_NEAR(size / target, 1.0, 0.05) << "c x" << c_factor;
  }
}

TEST(TrainRateControl, UpdatesAreBounded) {
  LambdaController control(1000, 1e-10f);
  EXPECT_FLOAT_EQ(control.Update(1000), 1e-10f);
  EXPECT_NEAR(control.Update(1000000), 3e-10f, 1e-15f);  // one factor of 3 at most
  EXPECT_NEAR(control.Update(1), 1e-10f, 1e-15f);
  EXPECT_THROW(LambdaController(0, 1e-10f), std::invalid_argument);
  EXPECT_THROW(LambdaController(10, 0.f), std::invalid_argument);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
