#include "tools/report/bd_rate.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace ecrf {
namespace tools {
namespace {

int Sign(double v) { return (v > 0) - (v < 0); }

// One-sided slope at an end knot (the three-point formula, limited so the curve stays monotone).
double EndSlope(double h0, double h1, double s0, double s1) {
  double d = ((2.0 * h0 + h1) * s0 - h0 * s1) / (h0 + h1);
  if (Sign(d) != Sign(s0)) {
    d = 0.0;
  } else if (Sign(s0) != Sign(s1) && std::fabs(d) > 3.0 * std::fabs(s0)) {
    d = 3.0 * s0;
  }
  return d;
}

// Antiderivatives of the cubic Hermite basis on t in [0, 1].
double H00(double t) { return t - t * t * t + t * t * t * t / 2.0; }
double H10(double t) { return t * t / 2.0 - 2.0 * t * t * t / 3.0 + t * t * t * t / 4.0; }
double H01(double t) { return t * t * t - t * t * t * t / 2.0; }
double H11(double t) { return -t * t * t / 3.0 + t * t * t * t / 4.0; }

// Sorts by x and rejects repeated x: a curve must be a function of the integration variable.
bool SortedStrictly(std::vector<std::pair<double, double>>* xy) {
  std::sort(xy->begin(), xy->end());
  for (size_t i = 1; i < xy->size(); ++i) {
    if (!((*xy)[i].first > (*xy)[i - 1].first)) return false;
  }
  return true;
}

Pchip MakeCurve(const std::vector<std::pair<double, double>>& xy) {
  std::vector<double> x, y;
  for (const auto& p : xy) {
    x.push_back(p.first);
    y.push_back(p.second);
  }
  return Pchip(std::move(x), std::move(y));
}

}  // namespace

Pchip::Pchip(std::vector<double> x, std::vector<double> y) : x_(std::move(x)), y_(std::move(y)) {
  const size_t n = x_.size();
  d_.assign(n, 0.0);
  if (n < 2) return;
  std::vector<double> h(n - 1), s(n - 1);
  for (size_t i = 0; i + 1 < n; ++i) {
    h[i] = x_[i + 1] - x_[i];
    s[i] = (y_[i + 1] - y_[i]) / h[i];
  }
  if (n == 2) {
    d_[0] = d_[1] = s[0];
    return;
  }
  for (size_t i = 1; i + 1 < n; ++i) {
    if (s[i - 1] * s[i] <= 0.0) continue;  // a local extremum: flat, so no overshoot
    const double w1 = 2.0 * h[i] + h[i - 1], w2 = h[i] + 2.0 * h[i - 1];
    d_[i] = (w1 + w2) / (w1 / s[i - 1] + w2 / s[i]);
  }
  d_[0] = EndSlope(h[0], h[1], s[0], s[1]);
  d_[n - 1] = EndSlope(h[n - 2], h[n - 3], s[n - 2], s[n - 3]);
}

double Pchip::operator()(double x) const {
  const size_t k = std::min<size_t>(
      x_.size() - 2, size_t(std::max<std::ptrdiff_t>(
                         0, std::upper_bound(x_.begin(), x_.end(), x) - x_.begin() - 1)));
  const double h = x_[k + 1] - x_[k], t = (x - x_[k]) / h;
  const double t2 = t * t, t3 = t2 * t;
  return (2 * t3 - 3 * t2 + 1) * y_[k] + (t3 - 2 * t2 + t) * h * d_[k] +
         (-2 * t3 + 3 * t2) * y_[k + 1] + (t3 - t2) * h * d_[k + 1];
}

double Pchip::Integral(double a, double b) const {
  double sum = 0.0;
  for (size_t k = 0; k + 1 < x_.size(); ++k) {
    const double lo = std::max(a, x_[k]), hi = std::min(b, x_[k + 1]);
    if (!(hi > lo)) continue;
    const double h = x_[k + 1] - x_[k];
    const double ta = (lo - x_[k]) / h, tb = (hi - x_[k]) / h;
    sum += h * (y_[k] * (H00(tb) - H00(ta)) + h * d_[k] * (H10(tb) - H10(ta)) +
                y_[k + 1] * (H01(tb) - H01(ta)) + h * d_[k + 1] * (H11(tb) - H11(ta)));
  }
  return sum;
}

std::vector<RdPoint> ParetoFront(const std::vector<RdPoint>& curve,
                                 std::vector<RdPoint>* dominated) {
  std::vector<RdPoint> front;
  for (const RdPoint& p : curve) {
    bool beaten = false;
    for (const RdPoint& q : curve) {
      beaten |= (q.rate <= p.rate && q.psnr > p.psnr) || (q.rate < p.rate && q.psnr >= p.psnr);
    }
    (beaten ? dominated : &front)->push_back(p);
  }
  return front;
}

BdResult Bjontegaard(const std::vector<RdPoint>& anchor_points,
                     const std::vector<RdPoint>& test_points) {
  BdResult r;
  // A point another point of its own curve beats (no larger and better, or smaller and no
  // worse) is not on the curve: a codec reaches the better one at that size. Left in, it folds
  // the curve back on itself and the interpolant over PSNR zigzags.
  const std::vector<RdPoint> anchor = ParetoFront(anchor_points, &r.dominated[0]);
  const std::vector<RdPoint> test = ParetoFront(test_points, &r.dominated[1]);
  if (anchor.size() < 2 || test.size() < 2) {
    r.error = "each curve needs at least two points that no other point of it beats";
    return r;
  }
  // BD-rate integrates log10(rate) over PSNR; BD-PSNR integrates PSNR over log10(rate).
  std::vector<std::pair<double, double>> a_by_psnr, t_by_psnr, a_by_rate, t_by_rate;
  for (int c = 0; c < 2; ++c) {
    for (const RdPoint& p : c == 0 ? anchor : test) {
      if (!(p.rate > 0.0) || !std::isfinite(p.rate) || !std::isfinite(p.psnr)) {
        r.error = "rates must be positive and PSNRs finite";
        return r;
      }
      (c == 0 ? a_by_psnr : t_by_psnr).emplace_back(p.psnr, std::log10(p.rate));
      (c == 0 ? a_by_rate : t_by_rate).emplace_back(std::log10(p.rate), p.psnr);
    }
  }
  if (!SortedStrictly(&a_by_psnr) || !SortedStrictly(&t_by_psnr)) {
    r.error = "two points of one curve have the same PSNR";
    return r;
  }
  if (!SortedStrictly(&a_by_rate) || !SortedStrictly(&t_by_rate)) {
    r.error = "two points of one curve have the same rate";
    return r;
  }
  const double plo = std::max(a_by_psnr.front().first, t_by_psnr.front().first);
  const double phi = std::min(a_by_psnr.back().first, t_by_psnr.back().first);
  const double rlo = std::max(a_by_rate.front().first, t_by_rate.front().first);
  const double rhi = std::min(a_by_rate.back().first, t_by_rate.back().first);
  const bool psnr_overlap = phi > plo, rate_overlap = rhi > rlo;
  if (!psnr_overlap && !rate_overlap) {
    r.error = "the curves overlap neither in PSNR nor in rate";
    return r;
  }
  const Pchip ap = MakeCurve(a_by_psnr), tp = MakeCurve(t_by_psnr);
  const Pchip ar = MakeCurve(a_by_rate), tr = MakeCurve(t_by_rate);
  if (psnr_overlap) {
    const double mean_log_diff = (tp.Integral(plo, phi) - ap.Integral(plo, phi)) / (phi - plo);
    r.bd_rate = (std::pow(10.0, mean_log_diff) - 1.0) * 100.0;
    r.psnr_range[0] = plo;
    r.psnr_range[1] = phi;
  } else {
    // The test curve above the anchor's PSNRs: its smallest file reaches all of them (at most
    // that rate). Below them: it needs more than its largest file (at least that rate).
    const bool above = t_by_psnr.front().first >= a_by_psnr.back().first;
    const double lo = a_by_psnr.front().first, hi = a_by_psnr.back().first;
    const double test_log_rate = above ? t_by_psnr.front().second : t_by_psnr.back().second;
    const double mean_log_diff = test_log_rate - ap.Integral(lo, hi) / (hi - lo);
    r.bd_rate = (std::pow(10.0, mean_log_diff) - 1.0) * 100.0;
    r.bd_rate_bound = above ? +1 : -1;
    r.psnr_range[0] = lo;
    r.psnr_range[1] = hi;
  }
  if (rate_overlap) {
    r.bd_psnr = (tr.Integral(rlo, rhi) - ar.Integral(rlo, rhi)) / (rhi - rlo);
    r.rate_range[0] = std::pow(10.0, rlo);
    r.rate_range[1] = std::pow(10.0, rhi);
  } else {
    // The test curve at smaller files than the anchor's: at any of the anchor's sizes it does
    // at least as well as its largest file. At larger files: no better than its smallest.
    const bool smaller = t_by_rate.back().first <= a_by_rate.front().first;
    const double lo = a_by_rate.front().first, hi = a_by_rate.back().first;
    const double test_psnr = smaller ? t_by_rate.back().second : t_by_rate.front().second;
    r.bd_psnr = test_psnr - ar.Integral(lo, hi) / (hi - lo);
    r.bd_psnr_bound = smaller ? -1 : +1;
    r.rate_range[0] = std::pow(10.0, lo);
    r.rate_range[1] = std::pow(10.0, hi);
  }
  r.ok = true;
  return r;
}

}  // namespace tools
}  // namespace ecrf
