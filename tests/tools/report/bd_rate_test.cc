#include "tools/report/bd_rate.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ecrf {
namespace tools {
namespace {

std::vector<RdPoint> Scaled(const std::vector<RdPoint>& curve, double rate_factor,
                            double psnr_offset = 0.0) {
  std::vector<RdPoint> out = curve;
  for (RdPoint& p : out) {
    p.rate *= rate_factor;
    p.psnr += psnr_offset;
  }
  return out;
}

// A curved, concave RD curve as codecs give (diminishing PSNR per doubled rate).
const std::vector<RdPoint> kAnchor = {
    {100e3, 30.0}, {200e3, 33.0}, {400e3, 35.2}, {800e3, 36.5}, {1600e3, 37.1}};

TEST(BdRate, TenPercentFewerBytesAtEveryPsnrIsMinusTenPercent) {
  const BdResult r = Bjontegaard(kAnchor, Scaled(kAnchor, 0.9));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_NEAR(r.bd_rate, -10.0, 1e-9);
  // And the other way round: the anchor needs 1/0.9 - 1 = 11.1% more.
  const BdResult back = Bjontegaard(Scaled(kAnchor, 0.9), kAnchor);
  ASSERT_TRUE(back.ok) << back.error;
  EXPECT_NEAR(back.bd_rate, 100.0 / 9.0, 1e-9);
  EXPECT_NEAR(r.psnr_range[0], 30.0, 1e-12);
  EXPECT_NEAR(r.psnr_range[1], 37.1, 1e-12);
}

TEST(BdRate, StraightLineInLogRateGivesTheExactPsnrShift) {
  // PSNR = 10 log10(rate) - 20: PCHIP reproduces straight lines exactly, so a curve that needs
  // 0.9x the rate is 10 log10(1 / 0.9) = 0.4576 dB higher at every rate.
  std::vector<RdPoint> line;
  for (double rate : {1e5, 3e5, 4e5, 9e5}) line.push_back({rate, 10.0 * std::log10(rate) - 20.0});
  const BdResult r = Bjontegaard(line, Scaled(line, 0.9));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_NEAR(r.bd_psnr, -10.0 * std::log10(0.9), 1e-9);
  EXPECT_NEAR(r.bd_rate, -10.0, 1e-9);
}

TEST(BdRate, PsnrOffsetOnly) {
  // Half a dB better everywhere: BD-PSNR +0.5 exactly; BD-rate negative.
  const BdResult r = Bjontegaard(kAnchor, Scaled(kAnchor, 1.0, 0.5));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_NEAR(r.bd_psnr, 0.5, 1e-9);
  EXPECT_LT(r.bd_rate, 0.0);
  const BdResult same = Bjontegaard(kAnchor, kAnchor);
  EXPECT_NEAR(same.bd_rate, 0.0, 1e-12);
  EXPECT_NEAR(same.bd_psnr, 0.0, 1e-12);
}

TEST(BdRate, PointOrderDoesNotMatter) {
  std::vector<RdPoint> shuffled = {kAnchor[3], kAnchor[0], kAnchor[4], kAnchor[1], kAnchor[2]};
  const std::vector<RdPoint> test = {{120e3, 30.5}, {500e3, 35.9}, {230e3, 33.4}, {1500e3, 37.3}};
  const BdResult a = Bjontegaard(kAnchor, test), b = Bjontegaard(shuffled, test);
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_DOUBLE_EQ(a.bd_rate, b.bd_rate);
  EXPECT_DOUBLE_EQ(a.bd_psnr, b.bd_psnr);
}

// A point its own curve beats (here a lambda = 0 run larger and worse than a rate point, as in
// the chair baseline) is left out of both integrals and listed: it would fold the curve back.
TEST(BdRate, PointsTheirOwnCurveBeatsAreLeftOut) {
  std::vector<RdPoint> with_dominated = kAnchor;
  with_dominated.push_back({1000e3, 36.0});  // larger than 800e3 at 36.5 dB, and worse
  with_dominated.push_back({400e3, 34.0});   // the size of 400e3 at 35.2 dB, and worse
  const BdResult clean = Bjontegaard(kAnchor, Scaled(kAnchor, 0.8));
  const BdResult r = Bjontegaard(with_dominated, Scaled(kAnchor, 0.8));
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_NEAR(r.bd_rate, clean.bd_rate, 1e-12);
  EXPECT_NEAR(r.bd_psnr, clean.bd_psnr, 1e-12);
  ASSERT_EQ(r.dominated[0].size(), 2u);
  EXPECT_EQ(r.dominated[0][0].rate, 1000e3);
  EXPECT_EQ(r.dominated[0][1].psnr, 34.0);
  EXPECT_TRUE(r.dominated[1].empty());
  // Without the front the same data gives another figure: the check has teeth.
  std::vector<RdPoint> front_only;
  std::vector<RdPoint> left;
  front_only = ParetoFront(with_dominated, &left);
  EXPECT_EQ(front_only.size(), kAnchor.size());
  EXPECT_EQ(left.size(), 2u);
}

// A curve wholly above the anchor's PSNRs has no BD-rate, only a bound: its smallest file reaches
// every PSNR of the anchor. With PSNR = 10 log10(rate) - 20 the anchor's mean log10 rate over its
// PSNR range is log10(sqrt(1e5 * 9e5)) = log10(3e5) exactly.
TEST(BdRate, CurvesThatDoNotOverlapInPsnrGiveABound) {
  std::vector<RdPoint> line;
  for (double rate : {1e5, 3e5, 4e5, 9e5}) line.push_back({rate, 10.0 * std::log10(rate) - 20.0});
  const BdResult above = Bjontegaard(line, {{2e5, 40.0}, {5e5, 41.0}});
  ASSERT_TRUE(above.ok) << above.error;
  EXPECT_EQ(above.bd_rate_bound, +1);
  EXPECT_NEAR(above.bd_rate, (2e5 / 3e5 - 1.0) * 100.0, 1e-9);
  EXPECT_NEAR(above.psnr_range[0], 30.0, 1e-12);
  EXPECT_NEAR(above.psnr_range[1], 10.0 * std::log10(9e5) - 20.0, 1e-12);
  EXPECT_EQ(above.bd_psnr_bound, 0);  // the rates overlap: BD-PSNR is a value
  EXPECT_GT(above.bd_psnr, 0.0);
  // Below the anchor's PSNRs: more than its largest file, so at least that.
  const BdResult below = Bjontegaard(line, {{2e5, 20.0}, {5e5, 25.0}});
  ASSERT_TRUE(below.ok) << below.error;
  EXPECT_EQ(below.bd_rate_bound, -1);
  EXPECT_NEAR(below.bd_rate, (5e5 / 3e5 - 1.0) * 100.0, 1e-9);
  // Files all smaller than the anchor's with overlapping PSNRs: BD-PSNR at least what its largest
  // file gives against the anchor's mean PSNR over its log rates ((30 + 39.54) / 2).
  const BdResult smaller = Bjontegaard(line, {{2e4, 31.0}, {5e4, 35.0}});
  ASSERT_TRUE(smaller.ok) << smaller.error;
  EXPECT_EQ(smaller.bd_rate_bound, 0);
  EXPECT_LT(smaller.bd_rate, -50.0);
  EXPECT_EQ(smaller.bd_psnr_bound, -1);
  EXPECT_NEAR(smaller.bd_psnr, 35.0 - (30.0 + 10.0 * std::log10(9e5) - 20.0) / 2.0, 1e-9);
  EXPECT_NEAR(smaller.rate_range[0], 1e5, 1e-6);
  EXPECT_NEAR(smaller.rate_range[1], 9e5, 1e-6);
}

TEST(BdRate, RefusesWhatCannotBeCompared) {
  EXPECT_FALSE(Bjontegaard({kAnchor[0]}, kAnchor).ok);
  EXPECT_FALSE(Bjontegaard(kAnchor, {{1e5, 30.0}, {2e5, 30.0}}).ok);  // same PSNR twice
  EXPECT_FALSE(Bjontegaard(kAnchor, {{1e9, 50.0}, {2e9, 51.0}}).ok);  // overlaps in neither
  EXPECT_FALSE(Bjontegaard(kAnchor, {{0.0, 31.0}, {2e5, 33.0}}).ok);  // rate 0
  const BdResult r = Bjontegaard(kAnchor, {{1e5, NAN}, {2e5, 33.0}});
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.error.empty());
}

TEST(Pchip, InterpolatesKnotsWithoutOvershootAndIntegratesExactly) {
  const std::vector<double> x = {0.0, 1.0, 1.5, 4.0, 5.0}, y = {0.0, 2.0, 2.1, 2.2, 6.0};
  const Pchip p(x, y);
  for (size_t i = 0; i < x.size(); ++i) EXPECT_NEAR(p(x[i]), y[i], 1e-12);
  // Monotone data: the interpolant never decreases and stays within each interval's values.
  double prev = p(0.0);
  double midpoint_sum = 0.0;
  const int n = 200000;
  for (int k = 1; k <= n; ++k) {
    const double v = p(5.0 * k / n);
    EXPECT_GE(v, prev - 1e-12);
    prev = v;
    midpoint_sum += p(5.0 * (k - 0.5) / n) * (5.0 / n);
  }
  EXPECT_NEAR(p.Integral(0.0, 5.0), midpoint_sum, 1e-8);
  // Sub-intervals add up.
  EXPECT_NEAR(p.Integral(0.3, 4.4), p.Integral(0.3, 1.2) + p.Integral(1.2, 4.4), 1e-12);
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
