// The ray marcher against the naive reference renderer of SPEC.md 7 (tests/common/
// naive_renderer.h): what the decoder's rendering tests share.
#ifndef ECRF_TESTS_COMMON_MARCHER_CHECKS_H_
#define ECRF_TESTS_COMMON_MARCHER_CHECKS_H_

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "decoder/ray_marcher.h"
#include "tests/common/naive_renderer.h"

namespace ecrf {
namespace dec {
namespace naive {

inline void RenderWith(const SceneField& s, const RenderOptions& opt, const Rays& rays,
                       std::vector<float>* rgb, std::vector<float>* acc,
                       RenderStats* stats = nullptr) {
  RayMarcher rm;
  const Status st = rm.Init(&s, opt);
  ASSERT_TRUE(st.ok()) << st.message();
  rgb->assign(rays.size() * 3, -1.f);
  acc->assign(rays.size(), -1.f);
  const Status r =
      rm.RenderRays(rays.size(), rays.o.data(), rays.d.data(), rgb->data(), acc->data(), stats);
  ASSERT_TRUE(r.ok()) << r.message();
}

inline void ExpectMatchesNaive(const TestScene& ts, const RenderOptions& opt, uint32_t seed,
                               double min_mean_acc = 0.05, double tol = 1e-4) {
  const Rays rays = MakeRays(ts.field, seed);
  std::vector<float> rgb, acc;
  RenderWith(ts.field, opt, rays, &rgb, &acc);
  double max_err = 0.0, max_acc_err = 0.0, sum_acc = 0.0;
  int worst = -1;
  for (size_t r = 0; r < rays.size(); ++r) {
    double ref[3], ref_acc;
    NaiveRender(ts, &rays.o[3 * r], &rays.d[3 * r], ref, &ref_acc);
    sum_acc += ref_acc;
    for (int k = 0; k < 3; ++k) {
      const double e = std::fabs(ref[k] - rgb[3 * r + k]);
      if (e > max_err) {
        max_err = e;
        worst = int(r);
      }
    }
    max_acc_err = std::max(max_acc_err, std::fabs(ref_acc - acc[r]));
    if (std::string(rays.kind[r]) == "miss") {
      EXPECT_EQ(acc[r], 0.f);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(rgb[3 * r + k], ts.field.background[k]);
    }
  }
  EXPECT_LT(max_err, tol) << "worst ray " << worst << " (" << (worst >= 0 ? rays.kind[worst] : "")
                          << ")";
  EXPECT_LT(max_acc_err, tol);
  // The scene must actually show something (not a trivially white image).
  EXPECT_GT(sum_acc / rays.size(), min_mean_acc);
}

inline RenderOptions Exact() {
  RenderOptions o;
  o.early_stop_transmittance = 0.f;
  o.tile_size = 4;
  o.batch_rows = 37;  // odd batch size: flushes in the middle of rays
  // The translucent test scenes colour hundreds of samples per ray without early termination:
  // more than a pixel's default work budget (decoder/render_work.h), which is not under test here.
  o.work_budget = 0;
  return o;
}

}  // namespace naive
}  // namespace dec
}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_MARCHER_CHECKS_H_
