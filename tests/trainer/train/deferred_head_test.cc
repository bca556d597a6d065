// The deferred head end to end (SPEC.md 7.6): the 1.6 stream that carries it, the decoder's
// renderer against the trainer's on the same field, the work the decoder charges for it, the
// checkpoint that keeps it, and --head auto's choice by the render budget. (Its gradients and
// training: tests/trainer/model/volume_render_test.cc.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "decoder/ray_marcher.h"
#include "decoder/render_work.h"
#include "encoder/scene_encoder.h"
#include "tests/common/decode_or_die.h"
#include "tests/common/renderer_agreement.h"
#include "tests/common/scoped_temp_dir.h"
#include "tests/common/small_model.h"
#include "trainer/data/camera.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/coded_model.h"
#include "trainer/train/head_choice.h"
#include "trainer/train/train_schedule.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace trainer {
namespace {

TensorfModel SmallDeferredModel(uint64_t seed, int hidden_layers = 2) {
  TensorfConfig c = testing_models::SmallTensorfConfig();
  c.head.kind = HeadKind::kDeferred;
  c.head.hidden_layers = hidden_layers;
  c.white_background = true;
  TensorfModel model(c);
  model.Initialize({12, 11, 10}, seed);
  // Larger head weights than the initialisation's: colours that differ between rays and heads.
  for (float& w : model.head().params()) w *= 4.f;
  return model;
}

encoder::EncodeOptions FloatMlpOptions() {
  encoder::EncodeOptions o;
  o.mlp_float32 = true;
  o.mlp_max_level = 0;
  o.drop_zero_components = false;
  return o;
}

// Rays through the box from a sphere of cameras, unit directions.
void SphereRays(int n, std::vector<float>* origins, std::vector<float>* dirs) {
  testing_models::RaysFromSphere(n, 3, origins, dirs);
}

TEST(DeferredHead, StreamIsVersion16AndTheDecoderRendersWhatTheTrainerRenders) {
  TensorfModel model = SmallDeferredModel(5);
  model.UpdateAlphaMask({9, 8, 9});
  const std::vector<uint8_t> bytes = EncodeScene(model, FloatMlpOptions());
  EXPECT_EQ(bytes[5], 6);  // version_minor: the deferred head is a 1.6 feature
  const dec::SceneField field = DecodeOrDie(bytes);
  ASSERT_EQ(field.head, HeadKind::kDeferred);
  EXPECT_EQ(field.StepSize(), model.step_size());  // the file declares the chosen spacing
  EXPECT_EQ(field.NumSamples(), model.n_samples());
  LoadDecodedGrids(field, &model);

  std::vector<float> origins, dirs;
  SphereRays(300, &origins, &dirs);
  const RendererAgreement r = RenderBothWays(model, field, origins, dirs);
  // Same samples, same sums of products: only the encoding's sin/cos and summation order differ.
  EXPECT_LT(r.worst, 2e-3f);
  EXPECT_GT(r.spread, 0.05f);  // the rays see different things
  EXPECT_GT(r.decoder_samples, origins.size() / 3 * 5);

  // The same field with the per-sample head renders differently: the head kind is not ignored.
  dec::SceneField mlp_field = DecodeOrDie(bytes);
  mlp_field.head = HeadKind::kPerSample;
  const RendererAgreement cross = RenderBothWays(model, mlp_field, origins, dirs);
  EXPECT_GT(cross.worst, 0.02f);
}

// hidden 0: spherical-harmonics colour (SPEC.md 7.6.2), a 1.7 feature, with either head; the
// decoder renders what the trainer renders, with float and with quantized weights.
TEST(DeferredHead, ShColourStreamIsVersion17AndRendersAsTheTrainer) {
  for (const HeadKind kind : {HeadKind::kDeferred, HeadKind::kPerSample}) {
    SCOPED_TRACE(HeadKindName(kind));
    TensorfConfig c = testing_models::SmallTensorfConfig();
    c.head.kind = kind;
    c.head.hidden = 0;
    c.head.feature_dim = 27;
    c.head.feature_pe_freqs = 0;
    c.head.viewdir_pe_freqs = 0;
    c.white_background = true;
    TensorfModel model(c);
    model.Initialize({12, 11, 10}, 9);
    for (float& w : model.head().params()) w *= 6.f;
    model.UpdateAlphaMask({9, 8, 9});
    for (const bool quantized : {false, true}) {
      encoder::EncodeOptions o = FloatMlpOptions();
      if (quantized) o.mlp_max_level = 127;  // precision 2, as ecrf encodes by default
      o.drop_zero_components = false;
      const std::vector<uint8_t> bytes = EncodeScene(model, o);
      EXPECT_EQ(bytes[5], 7);  // version_minor
      const dec::SceneField field = DecodeOrDie(bytes);
      ASSERT_EQ(field.mlp.config().hidden, 0);
      ASSERT_EQ(field.head, kind);
      TensorfModel decoded = model;
      LoadDecodedGrids(field, &decoded);
      if (quantized) {  // the decoder's weights, so that both render one field
        ASSERT_TRUE(
            field.mlp.GetParams(decoded.head().params().data(), decoded.head().params().size())
                .ok());
      }
      std::vector<float> origins, dirs;
      SphereRays(300, &origins, &dirs);
      const RendererAgreement r = RenderBothWays(decoded, field, origins, dirs);
      EXPECT_LT(r.worst, 2e-3f) << "quantized " << quantized;
      EXPECT_GT(r.spread, 0.05f);
    }
    encoder::EncodeOptions o = FloatMlpOptions();
    o.max_version_minor = 6;
    EXPECT_THROW(EncodeScene(model, o), std::invalid_argument);
  }
}

TEST(DeferredHead, EncoderRefusesAStreamVersionWithoutIt) {
  const TensorfModel model = SmallDeferredModel(6);
  encoder::EncodeOptions o = FloatMlpOptions();
  o.max_version_minor = 5;
  try {
    EncodeScene(model, o);
    FAIL() << "a 1.5 stream with a deferred head was written";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("needs stream version 1.6"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("deferred head"), std::string::npos) << e.what();
  }
}

// The decoder charges the MLP once per ray with a coloured sample, not once per coloured sample:
// the same field and rays cost less with the deferred head, by the MLP of the samples beyond the
// first of each ray.
TEST(DeferredHead, DecoderChargesTheMlpOncePerColouredRay) {
  const TensorfModel model = SmallDeferredModel(7);
  const std::vector<uint8_t> bytes = EncodeScene(model, FloatMlpOptions());
  dec::SceneField deferred = DecodeOrDie(bytes), per_sample = DecodeOrDie(bytes);
  per_sample.head = HeadKind::kPerSample;
  std::vector<float> origins, dirs;
  SphereRays(200, &origins, &dirs);
  const size_t n = origins.size() / 3;
  dec::RenderStats stats[2];
  const dec::SceneField* fields[2] = {&deferred, &per_sample};
  for (int k = 0; k < 2; ++k) {
    dec::RayMarcher marcher;
    ASSERT_TRUE(marcher.Init(fields[k], dec::RenderOptions()).ok());
    std::vector<float> rgb(n * 3);
    ASSERT_TRUE(
        marcher.RenderRays(n, origins.data(), dirs.data(), rgb.data(), nullptr, &stats[k]).ok());
  }
  EXPECT_EQ(stats[0].samples, stats[1].samples);
  EXPECT_EQ(stats[0].color_samples, stats[1].color_samples);
  ASSERT_GT(stats[0].color_samples, 4 * n);  // several coloured samples per ray
  const dec::SampleCosts d = dec::SceneSampleCosts(deferred), p = dec::SceneSampleCosts(per_sample);
  ASSERT_GT(p.color, d.color);
  // Per-sample: every coloured sample pays the MLP. Deferred: each coloured sample its taps and
  // its share of the sum, each ray with a coloured sample the MLP once; so the work saved is
  // exactly the colour samples' difference less a whole number (1..n) of heads.
  const uint64_t per_sample_saving = stats[0].color_samples * (p.color - d.color);
  const uint64_t saved = stats[1].work - stats[0].work;
  ASSERT_LT(saved, per_sample_saving);
  EXPECT_EQ((per_sample_saving - saved) % d.ray_head, 0u);
  const uint64_t coloured_rays = (per_sample_saving - saved) / d.ray_head;
  EXPECT_GE(coloured_rays, n / 2);
  EXPECT_LE(coloured_rays, n);
}

// Saves the model as a checkpoint in a temporary directory of its own and runs load(path) on it.
template <typename Load>
void WithCheckpointOf(TensorfModel& model, const Load& load) {
  const testing_util::ScopedTempDir dir("ecrf_deferred_ckpt");
  const std::string path = dir.path() + "/model.ckpt";
  SaveModelCheckpoint(path, model, 3, TrainOptions());
  load(path);
}

// The head's kind and hidden layers (one: bitstream 1.8) come back with its weights.
TEST(DeferredHead, CheckpointKeepsTheHead) {
  for (const int layers : {2, 1}) {
    TensorfModel model = SmallDeferredModel(8, layers);
    WithCheckpointOf(model, [&](const std::string& path) {
      const TensorfModel back = LoadModelFromCheckpoint(path);
      EXPECT_EQ(back.config().head.kind, HeadKind::kDeferred);
      EXPECT_EQ(back.config().head.hidden_layers, layers);
      EXPECT_EQ(back.head().params(), model.head().params());
    });
  }
}

// A short run of the built-in scene (the tiny preset), --head auto with this render budget.
TrainOptions AutoOptions(float budget) {
  TrainOptions o = PresetOptions("tiny");
  o.procedural_scene = ProceduralScene::kBuiltin;
  o.builtin_size = 32;
  o.builtin_views = 12;
  o.iters = 300;
  o.batch_rays = 256;
  o.progress_every = 100;
  o.head = HeadChoice::kAuto;
  o.render_budget = budget;
  return o;
}

TrainResult AutoRun(float budget, TensorfModel* model) {  // one run, one model
  const TrainOptions o = AutoOptions(budget);
  const Dataset train = LoadTrainingViews(o, "train");
  const Dataset test = LoadTrainingViews(o, "test");
  *model = TensorfModel(ConfigFor(o, train));
  const TrainResult r = Train(o, train, test, model, nullptr);
  EXPECT_EQ(r.head_choice.iteration, GridFinalIteration(o));
  EXPECT_GT(r.head_choice.iteration, 0);
  return r;
}

// One short run with a budget nothing meets: auto switches to the cheapest candidate, the
// deferred head with spherical-harmonics colour at twice the spacing, once the grid is final (a
// new head, no MLP), training goes on through the switch,
// and what it predicted is the decoder's own count of the work on the same rays, up to the
// marched positions the mask rejects (which the decoder charges and the prediction leaves out).
// Within a budget the first candidate that fits is taken.
TEST(HeadChoice, AutoSwitchesOverTheBudgetAndPredictsTheDecodersWork) {
  TensorfModel model(TensorfConfig{});
  const TrainResult r = AutoRun(1.f, &model);
  const std::vector<RenderCandidate>& c = r.head_choice.candidates;
  ASSERT_EQ(c.size(), 5u);
  EXPECT_EQ(c[0].head, HeadKind::kPerSample);
  for (size_t k = 1; k < 5; ++k) EXPECT_EQ(c[k].head, HeadKind::kDeferred);
  const float ratios[5] = {0.5f, 0.5f, 1.f, 0.5f, 1.f};
  for (size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(c[k].step_ratio, ratios[k]);
    EXPECT_EQ(c[k].sh_degree, k < 3 ? -1 : TrainOptions().sh_degree);
  }
  EXPECT_EQ(r.head_choice.chosen, 4);
  EXPECT_EQ(model.config().head.kind, HeadKind::kDeferred);
  EXPECT_EQ(model.head().config().kind, HeadKind::kDeferred);
  EXPECT_EQ(model.head().config().hidden, 0);  // the harmonics replaced the MLP
  EXPECT_EQ(model.config().head.hidden, 0);
  EXPECT_EQ(model.config().step_ratio, 1.f);
  // The same counts at each spacing; the harmonics save the MLP of each coloured ray.
  EXPECT_EQ(c[3].counts.samples, c[1].counts.samples);
  EXPECT_EQ(c[4].counts.samples, c[2].counts.samples);
  EXPECT_LT(c[3].work, c[1].work);
  EXPECT_LT(c[4].work, c[2].work);
  EXPECT_LT(c[1].work, 0.5 * c[0].work);
  EXPECT_GT(c[1].counts.coloured, 1.0);
  // Twice the spacing: about half the samples (the same rays, the same field).
  EXPECT_LT(c[2].counts.samples, 0.7 * c[1].counts.samples);
  EXPECT_GT(c[2].counts.samples, 0.3 * c[1].counts.samples);
  EXPECT_LT(c[2].work, c[1].work);
  EXPECT_GT(r.final_train_psnr, 20.0);  // trained on through the switch
  EXPECT_EQ(ChooseRender(c, 1e9).chosen, 0);
  EXPECT_EQ(ChooseRender(c, 0.0).chosen, 0);
  EXPECT_EQ(ChooseRender(c, 0.5 * (c[0].work + c[1].work)).chosen, 1);
  EXPECT_EQ(ChooseRender(c, 0.5 * (c[1].work + c[2].work)).chosen, 2);
  EXPECT_EQ(ChooseRender(c, 0.5 * (c[4].work + std::min(c[2].work, c[3].work))).chosen, 4);

  // Two whole test views (the choice itself looks at training views).
  std::vector<float> origins, dirs;
  const Dataset test = LoadTrainingViews(AutoOptions(1.f), "test");
  ASSERT_GE(test.views.size(), 2u);
  for (size_t v : {size_t(0), test.views.size() / 2}) {
    std::vector<float> o, d;
    GenerateRowRays(test.views[v].camera, 0, test.views[v].camera.height, &o, &d);
    origins.insert(origins.end(), o.begin(), o.end());
    dirs.insert(dirs.end(), d.begin(), d.end());
  }
  const int n = int(origins.size() / 3);
  const std::vector<double> predicted =
      PredictHeadWork(model, CountRayWork(model, n, origins.data(), dirs.data()));
  const dec::SceneField field = DecodeOrDie(EncodeScene(model, FloatMlpOptions()));
  ASSERT_EQ(field.head, HeadKind::kDeferred);
  dec::RayMarcher marcher;
  ASSERT_TRUE(marcher.Init(&field, dec::RenderOptions()).ok());
  std::vector<float> rgb(origins.size());
  dec::RenderStats stats;
  ASSERT_TRUE(
      marcher.RenderRays(size_t(n), origins.data(), dirs.data(), rgb.data(), nullptr, &stats).ok());
  const double measured = double(stats.work) / n;
  const double p = predicted[int(HeadKind::kDeferred)];
  EXPECT_LE(p, 1.02 * measured) << p << " predicted, " << measured << " measured";
  EXPECT_GE(p, 0.6 * measured) << p << " predicted, " << measured << " measured";
}

// Weighing the candidates leaves the model as it was; a new spacing keeps a ray's length.
TEST(HeadChoice, CandidatesRestoreTheSpacingAndSetStepRatioKeepsTheRayLength) {
  TensorfModel model = SmallDeferredModel(3);
  const float step = model.step_size();
  const int n_samples = model.n_samples();
  std::vector<float> origins = {0.f, -3.f, 0.2f, 0.1f, -3.f, 0.f};
  std::vector<float> dirs = {0.f, 1.f, 0.f, 0.f, 1.f, 0.05f};
  const std::vector<RenderCandidate> c = RenderCandidates(&model, 2, origins.data(), dirs.data());
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(model.step_size(), step);
  EXPECT_EQ(model.n_samples(), n_samples);
  model.SetStepRatio(2.f * model.config().step_ratio);
  EXPECT_FLOAT_EQ(model.step_size(), 2.f * step);
  EXPECT_EQ(model.n_samples(), (n_samples + 1) / 2);
  EXPECT_THROW(model.SetStepRatio(0.f), std::invalid_argument);
}

// A run that --head auto moved to twice the spacing resumes at it: the checkpoint's spacing and
// samples per ray replace the options' (which still say the spacing the run started with).
TEST(HeadChoice, ResumeKeepsTheSpacingAutoChose) {
  TensorfModel model = SmallDeferredModel(4);
  const float ratio = model.config().step_ratio;
  model.SetStepRatio(2.f * ratio);
  TensorfModel resumed(SmallDeferredModel(4).config());  // --resume: the options' model first
  WithCheckpointOf(model, [&](const std::string& path) {
    LoadModelCheckpoint(path, &resumed, nullptr, nullptr);
  });
  EXPECT_EQ(resumed.config().step_ratio, 2.f * ratio);
  EXPECT_EQ(resumed.step_size(), model.step_size());
  EXPECT_EQ(resumed.n_samples(), model.n_samples());
  EXPECT_EQ(EncodeScene(resumed, FloatMlpOptions()), EncodeScene(model, FloatMlpOptions()));
}

TEST(HeadChoice, TheBudgetComesFromTheFlagOrTheDeviceClass) {
  TrainOptions o;
  EXPECT_EQ(RenderBudget(o), 0.0);
  o.device_class = DeviceClassChoice::kPhone;
  EXPECT_EQ(RenderBudget(o), double(dec::kDeviceClasses[2].work_per_pixel));
  o.render_budget = 5000.f;
  EXPECT_EQ(RenderBudget(o), 5000.0);
  EXPECT_STREQ(NameOf(DeviceClassChoice::kPhone), "phone");
  EXPECT_STREQ(NameOf(HeadChoice::kDeferred), HeadKindName(HeadKind::kDeferred));
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
