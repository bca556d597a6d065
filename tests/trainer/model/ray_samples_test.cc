// The samples the trainer's renderer evaluates along a ray (trainer/model/ray_samples.h, through
// TraceRay): the points of TensoRF's sample_ray inside the box, with their density, alpha and
// weight, for rays along the axes, oblique, starting inside, missing the box or clipped by near.
#include "trainer/model/ray_samples.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "tests/common/small_model.h"
#include "trainer/model/volume_render.h"

namespace ecrf {
namespace trainer {
namespace {

void ExpectSamples(const TensorfModel& model, const float o[3], const float d[3], float jitter) {
  const auto samples = TraceRay(model, o, d, jitter);
  // Brute force over all samples as in TensoRF sample_ray.
  const Aabb& box = model.aabb();
  float te, tx;
  RayAabb(box, o, d, &te, &tx);
  const float t_min = std::min(std::max(te, model.config().near), model.config().far);
  std::vector<float> expect;
  for (int i = 0; i + 1 < model.n_samples(); ++i) {
    const float t = t_min + model.step_size() * (static_cast<float>(i) + jitter);
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      const float x = o[a] + d[a] * t;
      inside &= x >= box.min[a] && x <= box.max[a];
    }
    if (inside) expect.push_back(t);
  }
  ASSERT_EQ(samples.size(), expect.size());
  double T = 1;
  for (size_t k = 0; k < expect.size(); ++k) {
    EXPECT_FLOAT_EQ(samples[k].t, expect[k]);
    const float x[3] = {o[0] + d[0] * expect[k], o[1] + d[1] * expect[k], o[2] + d[2] * expect[k]};
    const double sigma = model.Sigma(x);
    EXPECT_NEAR(samples[k].sigma, sigma, 1e-6 * (1 + sigma));
    const double alpha = 1 - std::exp(-sigma * model.step_size() * model.config().distance_scale);
    EXPECT_NEAR(samples[k].alpha, alpha, 1e-6);
    EXPECT_NEAR(samples[k].weight, alpha * T, 1e-6);
    EXPECT_EQ(samples[k].colour, samples[k].weight > model.config().weight_threshold);
    T *= (1 - alpha) + 1e-10;
  }
}

TEST(RaySamplesTest, RaySamplingAxisParallelAndInside) {
  TensorfConfig c = testing_models::TinyTensorfConfig();
  c.density_shift = 0.f;
  TensorfModel model(c);
  model.Initialize({11, 11, 11}, 4);
  ASSERT_FLOAT_EQ(model.step_size(), 0.1f);
  {
    const float o[3] = {-3.f, 0.05f, 0.05f}, d[3] = {1.f, 0.f, 0.f};
    EXPECT_EQ(TraceRay(model, o, d, 0.3f).size(), 20u);  // x = -1 + 0.1 (i + 0.3) <= 1
    ExpectSamples(model, o, d, 0.3f);
    ExpectSamples(model, o, d, 0.f);
  }
  {
    const float o[3] = {0.1f, 0.2f, 0.f}, d[3] = {0.f, 0.f, -1.f};  // starts inside, t_min = near
    EXPECT_EQ(TraceRay(model, o, d, 0.5f).size(), 10u);             // z = -0.1 (i + 0.5) >= -1
    ExpectSamples(model, o, d, 0.5f);
  }
  {
    const float o[3] = {0.3f, -2.f, 3.f}, d[3] = {0.f, 0.6f, -0.8f};  // oblique
    ExpectSamples(model, o, d, 0.77f);
  }
  {
    const float o[3] = {-3.f, 1.5f, 0.f}, d[3] = {1.f, 0.f, 0.f};  // misses the box
    EXPECT_TRUE(TraceRay(model, o, d, 0.2f).empty());
  }
  TensorfConfig far_near = c;
  far_near.near = 2.f;  // starts inside but near clips past the exit
  TensorfModel m2(far_near);
  m2.Initialize({11, 11, 11}, 4);
  const float o[3] = {0.f, 0.f, 0.f}, d[3] = {0.f, 1.f, 0.f};
  EXPECT_TRUE(TraceRay(m2, o, d, 0.2f).empty());
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
