#include "encoder/encode_rate_control.h"

#include <gtest/gtest.h>

#include <stdexcept>

#include "trainer/model/tensorf_model.h"
#include "trainer/rate/coded_model.h"
#include "trainer/train/rate_state.h"

namespace ecrf {
namespace trainer {
namespace {

TensorfModel Model() {
  TensorfConfig c;
  c.density_ranks = {4, 4, 4};
  c.app_ranks = {6, 6, 6};
  c.head.num_products = 18;
  c.head.feature_dim = 6;
  c.head.hidden = 16;
  TensorfModel model(c);
  model.Initialize({40, 36, 32}, 5);
  return model;
}

TEST(EncodeRateControl, LandsJustUnderEachTarget) {
  const TensorfModel model = Model();
  encoder::EncodeOptions o;
  o.blocks.plane_block[0] = 4;  // blocks never span more channels than a mode has
  const size_t full = EncodeScene(model, o).size();
  for (double fraction : {0.8, 0.5, 0.3}) {
    const size_t target = size_t(fraction * double(full));
    const encoder::TargetSizeResult r = EncodeToTargetSize(model, o, target);
    EXPECT_LE(r.bytes.size(), target) << fraction;
    EXPECT_GE(double(r.bytes.size()), 0.95 * double(target)) << fraction;
    EXPECT_GT(r.step_scale, 1.0);
    EXPECT_EQ(r.report.total_bytes, r.bytes.size());
  }
  // A budget above the full-precision file: that file, unscaled.
  const encoder::TargetSizeResult same = EncodeToTargetSize(model, o, 2 * full);
  EXPECT_EQ(same.bytes, EncodeScene(model, o));
  EXPECT_EQ(same.step_scale, 1.0);
  // Below what the MLP alone needs: an error that says how far it can go.
  try {
    EncodeToTargetSize(model, o, 100);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("smallest file"), std::string::npos) << e.what();
  }
}

// Steps trained 4x coarser than the 8-bit peak step leave room below: a target above their file is
// reached with finer steps, never finer than the peak step (no coefficient clips).
TEST(EncodeRateControl, RefinesCoarseStepsUpToThePeakStep) {
  const TensorfModel model = Model();
  encoder::EncodeOptions o;
  o.blocks.plane_block[0] = 4;
  const std::vector<float> peak = ChooseQuantSteps(model, o.blocks, o.coef_bits);
  EXPECT_DOUBLE_EQ(encoder::FinestStepScale(DescribeModel(model), o, peak), 1.0);
  for (float s : peak) o.steps.push_back(4.f * s);
  EXPECT_NEAR(encoder::FinestStepScale(DescribeModel(model), o, o.steps), 0.25, 1e-6);
  const size_t coarse = EncodeScene(model, o).size();
  encoder::EncodeOptions at_peak = o;
  at_peak.steps = peak;
  const size_t finest = EncodeScene(model, at_peak).size();
  ASSERT_GT(finest, coarse + coarse / 10);

  const size_t target = (coarse + finest) / 2;
  const encoder::TargetSizeResult r = EncodeToTargetSize(model, o, target);
  EXPECT_LE(r.bytes.size(), target);
  EXPECT_GE(double(r.bytes.size()), 0.95 * double(target));
  EXPECT_LT(r.step_scale, 1.0);
  EXPECT_GE(r.step_scale, 0.25 - 1e-9);
  // Above the finest file: the finest file, at the peak steps.
  const encoder::TargetSizeResult top = EncodeToTargetSize(model, o, 2 * finest);
  EXPECT_NEAR(top.step_scale, 0.25, 1e-6);
  EXPECT_EQ(top.bytes.size(), finest);
}

TEST(EncodeRateControl, ParsesSizes) {
  EXPECT_EQ(encoder::ParseByteSize("500KB"), 500000u);
  EXPECT_EQ(encoder::ParseByteSize("1.2MB"), 1200000u);
  EXPECT_EQ(encoder::ParseByteSize("300000"), 300000u);
  EXPECT_EQ(encoder::ParseByteSize("2KiB"), 2048u);
  EXPECT_EQ(encoder::ParseByteSize("500kb"), 500000u);  // units in any case
  EXPECT_EQ(encoder::ParseByteSize("1mib"), 1048576u);
  EXPECT_EQ(encoder::ParseByteSize("7b"), 7u);
  for (const char* bad : {"", "KB", "-5KB", "12 parsecs", "1e99MB", "nan"}) {
    EXPECT_THROW(encoder::ParseByteSize(bad), std::invalid_argument) << bad;
  }
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
