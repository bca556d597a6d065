// Small TensoRF models, block shapes and rays for tests that render: a 2x2x2 box seen from a
// sphere of radius 3, a head of 16 hidden units, blocks that fit grids of a few dozen cells.
#ifndef ECRF_TESTS_COMMON_SMALL_MODEL_H_
#define ECRF_TESTS_COMMON_SMALL_MODEL_H_

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "encoder/coded_tensors.h"
#include "trainer/model/tensorf_model.h"

namespace ecrf {
namespace testing_models {

// Ranks 2,2,2 (density) and 3,3,3 (appearance), the default 27 features, 16 hidden units, the box
// [-1, 1]^3, near 0, far 10.
inline trainer::TensorfConfig TinyTensorfConfig() {
  trainer::TensorfConfig c;
  c.density_ranks = {2, 2, 2};
  c.app_ranks = {3, 3, 3};
  c.head.num_products = 9;
  c.head.hidden = 16;
  c.aabb.min = {-1.f, -1.f, -1.f};
  c.aabb.max = {1.f, 1.f, 1.f};
  c.near = 0.f;
  c.far = 10.f;
  return c;
}

// Ranks 3,4,2 (density) and 5,3,4 (appearance), 6 features, 16 hidden units, the box [-1, 1]^3,
// near 0, far 10, density shift -1, grids initialised at 0.4 N(0, 1).
inline trainer::TensorfConfig SmallTensorfConfig() {
  trainer::TensorfConfig c;
  c.density_ranks = {3, 4, 2};
  c.app_ranks = {5, 3, 4};
  c.head.num_products = 12;
  c.head.feature_dim = 6;
  c.head.hidden = 16;
  c.aabb.min = {-1.f, -1.f, -1.f};
  c.aabb.max = {1.f, 1.f, 1.f};
  c.near = 0.f;
  c.far = 10.f;
  c.density_shift = -1.f;
  c.init_scale = 0.4f;
  return c;
}

// A model every grid value of which shows in the colours, for tests that perturb the grids and
// read the rendered error: ranks 4,4,4 for both grids (extents that are multiples of
// SmallRateBlocks, so no edge padding), a dense medium (density shift +1), every sample coloured
// (weight threshold 0: no sample switches on or off under a perturbation), grids initialised on a
// 16^3 grid (seed 5), and a head 6x steeper than a fresh one, so that colours depend on the
// features as a trained head's do.
inline trainer::TensorfModel DenseSmallModel(int hidden_layers = 2) {
  trainer::TensorfConfig c = SmallTensorfConfig();
  c.head.hidden_layers = hidden_layers;
  c.density_ranks = {4, 4, 4};
  c.app_ranks = {4, 4, 4};
  c.density_shift = 1.f;
  c.weight_threshold = 0.f;
  trainer::TensorfModel model(c);
  model.Initialize({16, 16, 16}, 5);
  for (float& w : model.head().params()) w *= 6.f;
  return model;
}

// Plane blocks 4 x 8 x 4 (channel x H x W), line blocks 1 x 2 x 8.
inline encoder::RateConfig SmallRateBlocks() {
  encoder::RateConfig b;
  b.plane_block[0] = 4;
  b.plane_block[1] = 8;
  b.plane_block[2] = 4;
  b.line_block[1] = 2;
  b.line_block[2] = 8;
  return b;
}

// n rays from random points of the sphere of radius 3 towards random points of [-0.8, 0.8]^3,
// unit directions; o and d get n x 3 floats.
inline void RaysFromSphere(int n, uint32_t seed, std::vector<float>* o, std::vector<float>* d) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> nd;
  std::uniform_real_distribution<float> u(-0.8f, 0.8f);
  o->resize(3 * static_cast<size_t>(n));
  d->resize(3 * static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    float p[3] = {nd(rng), nd(rng), nd(rng)};
    const float len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    float q[3] = {u(rng), u(rng), u(rng)};
    float dir[3];
    for (int a = 0; a < 3; ++a) {
      (*o)[3 * i + a] = 3.f * p[a] / len;
      dir[a] = q[a] - (*o)[3 * i + a];
    }
    const float dl = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (int a = 0; a < 3; ++a) (*d)[3 * i + a] = dir[a] / dl;
  }
}

}  // namespace testing_models
}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_SMALL_MODEL_H_
