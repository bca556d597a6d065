// The unbounded scene model end to end: the contraction and its sampling (SPEC.md 7.2.1), the
// fitted region of interest and the automatic choice of model, the trainer's renderer against
// the decoder's on the same contracted field, and the 1.2 stream that carries it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "decoder/contraction.h"
#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"
#include "encoder/scene_encoder.h"
#include "format/byte_io.h"
#include "format/scene_header.h"
#include "tests/common/decode_or_die.h"
#include "tests/common/renderer_agreement.h"
#include "trainer/data/scene_fit.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/coded_model.h"
#include "trainer/scenes/builtin_scene.h"
#include "trainer/scenes/capture_scene.h"
#include "trainer/scenes/still_life.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace trainer {
namespace {

TEST(Contraction, IsMonotoneContinuousAndInvertible) {
  EXPECT_EQ(ContractCoordinate(0.5f), 0.5f);
  EXPECT_EQ(ContractCoordinate(1.f), 1.f);
  EXPECT_EQ(ContractCoordinate(-1.f), -1.f);
  EXPECT_EQ(ContractCoordinate(std::numeric_limits<float>::infinity()), 2.f);
  EXPECT_EQ(ContractCoordinate(-std::numeric_limits<float>::infinity()), -2.f);
  EXPECT_TRUE(std::isnan(ContractCoordinate(std::nanf(""))));
  // Continuous with slope 1 on both sides of |x| = 1.
  EXPECT_NEAR(ContractCoordinate(1.0001f), 1.0001f, 1e-7f);
  EXPECT_NEAR(ContractCoordinate(-1.0001f), -1.0001f, 1e-7f);
  float previous = -2.f;
  for (float x = -1e6f; x < 1e6f;
       x = x < 0 ? (x < -2.f ? x / 1.1f : x + 0.01f) : (x < 2.f ? x + 0.01f : x * 1.1f)) {
    const float y = ContractCoordinate(x);
    ASSERT_GE(y, previous) << x;
    ASSERT_GT(y, -2.f);
    ASSERT_LT(y, 2.f);
    EXPECT_NEAR(UncontractCoordinate(y), x, 1e-5f * std::max(1.f, x * x)) << x;
    previous = y;
  }
}

ContractedRay UnitRoiRay(const float o[3], const float d[3], float step) {
  // (1 / 2) * 2: the ROI [-1, 1]^3 is its own normalisation.
  const float roi_min[3] = {-1.f, -1.f, -1.f}, roi_scale[3] = {1.f, 1.f, 1.f};
  return ContractedRay(o, d, roi_min, roi_scale, step);
}

TEST(Contraction, SamplesAreEvenlySpacedInContractedDistanceAndEndAtTheEdge) {
  const float o[3] = {0.f, 0.f, 0.f}, d[3] = {1.f, 0.f, 0.f};
  const ContractedRay ray = UnitRoiRay(o, d, 0.01f);
  float t = 0.f, q[3], x[3], last_x = 0.f;
  int samples = 0;
  for (; samples < 100000; ++samples) {
    ray.At(t, q, x);
    if (samples > 0) {
      // Inside the ROI the step is exact; outside it shrinks towards the edge (Euler steps).
      // (At the very edge 2 - 1/q rounds to 2 in binary32: the last few samples coincide.)
      EXPECT_LE(x[0] - last_x, 0.0100005f) << samples;
      EXPECT_GE(x[0] - last_x, 0.f) << samples;
    }
    last_x = x[0];
    const float next = t + ray.Increment(q);
    if (!std::isfinite(next)) break;
    t = next;
  }
  // 1 unit inside the ROI (100 steps) and 1 contracted unit outside: a few hundred samples at
  // most, far below 12 / step.
  EXPECT_GT(samples, 150);
  EXPECT_LT(samples, 400);
  EXPECT_GT(last_x, 1.99f);
}

TEST(SceneFit, CaptureIsUnboundedWithASmallBoxAroundTheStillLife) {
  const Dataset train = MakeCaptureScene("train", 48, 36, 32, 7);
  const SceneFit fit = FitScene(SceneType::kAuto, train);
  EXPECT_EQ(fit.model, SceneModel::kUnbounded) << fit.reason;
  EXPECT_FALSE(fit.forward_facing);
  // The still life: the slab [-1, 1]^2 x [bottom, -0.4] and the objects on it up to z 0.95.
  for (int a = 0; a < 2; ++a) {
    EXPECT_LE(fit.roi.min[a], -1.f);
    EXPECT_GE(fit.roi.max[a], 1.f);
  }
  EXPECT_LE(fit.roi.min[2], float(procedural::kStillLifeBottom));
  EXPECT_GE(fit.roi.max[2], 0.95f);
  // And a small part of the aabb_scale 4 cube (about 12.1 units a side).
  EXPECT_LT(fit.roi_share, 0.03);
  std::printf("  fitted box [%.2f %.2f %.2f] - [%.2f %.2f %.2f], %.2f%% of the cube\n",
              fit.roi.min[0], fit.roi.min[1], fit.roi.min[2], fit.roi.max[0], fit.roi.max[1],
              fit.roi.max[2], 100 * fit.roi_share);
}

// The region of interest is fitted on a lattice over the dataset box and again on one over what
// the first found, so it does not grow with the box: Instant-NGP's aabb_scale 16 (what
// `ecrf prepare` writes) gives the box that aabb_scale 4 gives, to within a step of the second
// lattice (with the first lattice alone it was 1.6x larger in volume on a rendered capture).
TEST(SceneFit, RegionOfInterestDoesNotDependOnTheDatasetBoxSize) {
  const Dataset train = MakeCaptureScene("train", 48, 36, 32, 7);
  const double(&box)[2][3] = train.scene_aabb;
  std::vector<Camera> cameras;
  for (const View& v : train.views) cameras.push_back(v.camera);
  double big[2][3];
  for (int a = 0; a < 3; ++a) {
    const double mid = 0.5 * (box[0][a] + box[1][a]), half = 0.5 * (box[1][a] - box[0][a]);
    big[0][a] = mid - 4 * half;
    big[1][a] = mid + 4 * half;
  }
  const Aabb small_fit = FitRegionOfInterest(cameras, box);
  const Aabb big_fit = FitRegionOfInterest(cameras, big);
  for (int a = 0; a < 3; ++a) {
    const double extent = small_fit.max[a] - small_fit.min[a];
    // One step of the second lattice is extent / 63 / 1.2 of the unwidened box; allow two.
    EXPECT_NEAR(big_fit.min[a], small_fit.min[a], 2.0 * extent / 63) << "axis " << a;
    EXPECT_NEAR(big_fit.max[a], small_fit.max[a], 2.0 * extent / 63) << "axis " << a;
  }
}

// The auto weight threshold: unbounded scenes colour only samples above
// kUnboundedWeightThreshold (their hazy background sent ~100 samples a ray through the MLP), object
// scenes keep TensoRF's 1e-4, and an explicit --weight-threshold wins; the encoder writes it.
TEST(SceneFit, AutoWeightThresholdIsCoarserForUnboundedScenesOnly) {
  TrainOptions o = PresetOptions("tiny");
  const Dataset capture = MakeCaptureScene("train", 48, 36, 32, 7);
  const Dataset object = MakeBuiltinScene("train", 32, 32, 8, 7);
  ASSERT_EQ(FitScene(SceneType::kAuto, capture).model, SceneModel::kUnbounded);
  ASSERT_EQ(FitScene(SceneType::kAuto, object).model, SceneModel::kObject);
  EXPECT_EQ(ConfigFor(o, capture).weight_threshold, kUnboundedWeightThreshold);
  EXPECT_EQ(ConfigFor(o, object).weight_threshold, 1e-4f);
  o.weight_threshold = 2e-4f;
  EXPECT_EQ(ConfigFor(o, capture).weight_threshold, 2e-4f);
  o.weight_threshold = 0.f;
  EXPECT_EQ(ConfigFor(o, object).weight_threshold, 0.f);
  TensorfModel model(ConfigFor(PresetOptions("tiny"), capture));
  model.Initialize({16, 16, 16}, 3);
  const dec::SceneField field = DecodeOrDie(EncodeScene(model, encoder::EncodeOptions()));
  EXPECT_EQ(field.weight_threshold, kUnboundedWeightThreshold);
}

TEST(SceneFit, BlenderLayoutStaysAnObjectAndNamesAreChecked) {
  const Dataset train = MakeBuiltinScene("train", 32, 32, 20, 3);
  EXPECT_EQ(FitScene(SceneType::kAuto, train).model, SceneModel::kObject);
  EXPECT_EQ(FitScene(SceneType::kUnbounded, train).model, SceneModel::kUnbounded);
  EXPECT_THROW(ChoiceFromName<SceneType>("ndc", "--scene-type"), std::invalid_argument);
  EXPECT_EQ(ChoiceFromName<SceneType>("forward", "--scene-type"), SceneType::kForward);
  for (const std::string& name : TypedNames<SceneType>()) {  // every name reads back as itself
    EXPECT_EQ(NameOf(ChoiceFromName<SceneType>(name, "test")), name);
  }
}

TensorfModel SmallUnboundedModel(uint64_t seed) {
  TensorfConfig c;
  c.density_ranks = {2, 3, 2};
  c.app_ranks = {3, 2, 3};
  c.head.num_products = 8;
  c.head.feature_dim = 6;
  c.head.hidden = 16;
  c.scene_model = SceneModel::kUnbounded;
  c.roi.min = {-1.f, -0.8f, -0.5f};
  c.roi.max = {1.f, 0.9f, 0.5f};
  c.aabb.min = {-2.f, -2.f, -2.f};
  c.aabb.max = {2.f, 2.f, 2.f};
  c.near = 0.05f;
  c.far = 8.f;
  c.white_background = false;
  c.density_shift = -3.f;
  TensorfModel model(c);
  model.Initialize({17, 15, 16}, seed);
  return model;
}

TEST(UnboundedScene, StreamIsVersion12AndTheDecoderRendersWhatTheTrainerRenders) {
  TensorfModel model = SmallUnboundedModel(5);
  model.UpdateAlphaMask({9, 8, 9});  // a mask over the contracted cube
  encoder::EncodeOptions o;
  o.mlp_float32 = true;
  o.mlp_max_level = 0;
  o.drop_zero_components = false;
  o.max_version_minor = 3;
  const std::vector<uint8_t> bytes = EncodeScene(model, o);
  EXPECT_EQ(bytes[5], 2);  // version_minor: the unbounded model is a 1.2 feature
  const dec::SceneField field = DecodeOrDie(bytes);
  ASSERT_EQ(field.scene_model, SceneModel::kUnbounded);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(field.aabb_min[a], model.config().roi.min[a]);
    EXPECT_EQ(field.aabb_max[a], model.config().roi.max[a]);
    EXPECT_EQ(field.mask.aabb_min()[a], -2.f);
  }
  EXPECT_EQ(field.n_samples, model.n_samples());
  LoadDecodedGrids(field, &model);

  // Rays from inside and outside the region of interest in every direction.
  std::vector<float> origins, dirs;
  for (int r = 0; r < 200; ++r) {
    const float u = float(r) * 0.61803f, v = float(r) * 0.2719f;
    const float o3[3] = {r % 2 ? 0.3f : 2.5f * std::cos(u), r % 2 ? -0.2f : 2.5f * std::sin(u),
                         0.1f * (r % 5)};
    float d3[3] = {std::cos(u + v) * std::cos(v), std::sin(u + v) * std::cos(v), std::sin(v)};
    const float n = std::sqrt(d3[0] * d3[0] + d3[1] * d3[1] + d3[2] * d3[2]);
    for (int a = 0; a < 3; ++a) {
      origins.push_back(o3[a]);
      dirs.push_back(d3[a] / n);
    }
  }
  const RendererAgreement r = RenderBothWays(model, field, origins, dirs);
  // Same samples, same field: only the MLP's sin/cos approximations and summation order differ.
  EXPECT_LT(r.worst, 2e-3f);
  EXPECT_GT(r.spread, 0.01f);  // the rays see different things
  EXPECT_GT(r.decoder_samples, origins.size() / 3 * 20);

  // The trainer's samples are the decoder's: same positions, same intervals.
  const std::vector<RaySampleInfo> trace = TraceRay(model, origins.data(), dirs.data(), 0.f);
  ASSERT_FALSE(trace.empty());
  EXPECT_EQ(trace[0].t, model.config().near);
}

TEST(UnboundedScene, TrainStepLowersTheLossThroughTheContraction) {
  TensorfModel model = SmallUnboundedModel(6);
  std::vector<float> origins, dirs, target;
  for (int r = 0; r < 256; ++r) {
    const float u = float(r) * 0.37f;
    const float o3[3] = {0.f, 0.f, 0.f};
    const float d3[3] = {std::cos(u), std::sin(u), 0.f};
    for (int a = 0; a < 3; ++a) {
      origins.push_back(o3[a]);
      dirs.push_back(d3[a]);
    }
    target.push_back(0.8f);
    target.push_back(0.3f * (1 + std::cos(u)));
    target.push_back(0.1f);
  }
  double first = 0, last = 0;
  for (int it = 0; it < 60; ++it) {
    model.ZeroGrads();
    const TrainStepStats s = TrainStep(model, 256, origins.data(), dirs.data(), target.data(), it);
    if (it == 0) first = s.loss;
    last = s.loss;
    for (auto& a : model.NamedParameters()) {
      for (size_t i = 0; i < a.size; ++i) a.data[i] -= 0.5f * a.grad[i];
    }
  }
  EXPECT_LT(last, 0.5 * first);
}

TEST(UnboundedScene, HeaderRefusesUnknownSceneModelsAndNegativeNear) {
  SceneHeader h;
  h.ranks[1][0] = 1;
  h.step_size = 0.1f;
  h.num_samples = 10;
  for (uint8_t model : {uint8_t(0), uint8_t(1), uint8_t(2), uint8_t(255)}) {
    h.scene_model = model;
    ByteWriter w;
    WriteSceneHeader(h, 0, &w);
    SceneHeader parsed;
    const Status s = ParseSceneHeader(w.bytes().data(), w.bytes().size(), 0, &parsed);
    if (model < kNumSceneModels) {
      EXPECT_TRUE(s.ok()) << s.message();
      EXPECT_EQ(parsed.scene_model, model);
    } else {
      EXPECT_EQ(s.code(), kErrUnsupported) << s.message();
    }
  }
  h.scene_model = 1;
  h.near_far[0] = -0.5f;
  ByteWriter w;
  WriteSceneHeader(h, 0, &w);
  SceneHeader parsed;
  EXPECT_EQ(ParseSceneHeader(w.bytes().data(), w.bytes().size(), 0, &parsed).code(), kErrCorrupt);
  h.scene_model = 0;  // an object scene may start before its camera, as TensoRF's near allows
  ByteWriter w0;
  WriteSceneHeader(h, 0, &w0);
  EXPECT_TRUE(ParseSceneHeader(w0.bytes().data(), w0.bytes().size(), 0, &parsed).ok());
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
