// Bjøntegaard delta rate and delta PSNR between two rate–distortion curves (VCEG-M33), with
// piecewise cubic Hermite interpolation (PCHIP, Fritsch–Carlson slopes) as current codec test
// conditions use instead of the original single cubic fit: it follows the measured points
// without overshoot and works from two points on.
#ifndef ECRF_TOOLS_REPORT_BD_RATE_H_
#define ECRF_TOOLS_REPORT_BD_RATE_H_

#include <string>
#include <vector>

namespace ecrf {
namespace tools {

struct RdPoint {
  double rate = 0.0;  // bytes (any positive unit; only ratios matter)
  double psnr = 0.0;  // dB
};

struct BdResult {
  bool ok = false;
  std::string error;     // why not, when !ok
  double bd_rate = 0.0;  // percent: mean rate change of test against anchor at equal PSNR
  double bd_psnr = 0.0;  // dB: mean PSNR change of test against anchor at equal rate
  double psnr_range[2] = {0.0, 0.0};  // the overlap BD-rate integrates over
  double rate_range[2] = {0.0, 0.0};  // the overlap BD-PSNR integrates over
  // 0: the value. Where one curve lies wholly beyond the other's PSNRs (or rates), the value is
  // a bound instead: +1 the true figure is at most bd_rate (bd_psnr), -1 at least; the range is
  // then the anchor's own. See Bjontegaard.
  int bd_rate_bound = 0;
  int bd_psnr_bound = 0;
  std::vector<RdPoint> dominated[2];  // points of the anchor / test left out (ParetoFront)
};

// The points of `curve` that no other point of it beats: none has a rate no larger and a higher
// PSNR, or a smaller rate and a PSNR no lower. The others go to *dominated (in input order).
std::vector<RdPoint> ParetoFront(const std::vector<RdPoint>& curve,
                                 std::vector<RdPoint>* dominated);

// Over the Pareto fronts of both curves (dominated points are left out and listed in the
// result). Needs >= 2 such points per curve with distinct positive rates and distinct PSNRs, and
// overlapping PSNR or rate ranges. Points may come in any order. Where the PSNR ranges do not
// overlap (the test curve is better, or worse, at every size both reach), BD-rate is bounded over
// the anchor's PSNR range with the test curve held at its nearest end point: a file that reaches
// a PSNR also reaches every lower one, so the test's smallest file bounds its rate from above
// (its largest from below when it never reaches the anchor's PSNRs). BD-PSNR likewise when the
// rates do not overlap.
BdResult Bjontegaard(const std::vector<RdPoint>& anchor, const std::vector<RdPoint>& test);

// Monotone piecewise cubic Hermite interpolant through (x[i], y[i]), x strictly increasing.
class Pchip {
 public:
  Pchip(std::vector<double> x, std::vector<double> y);
  double operator()(double x) const;
  // Exact integral of the interpolant over [a, b] within [x.front(), x.back()].
  double Integral(double a, double b) const;

 private:
  std::vector<double> x_, y_, d_;  // d_: slopes at the knots
};

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_REPORT_BD_RATE_H_
