// The deferred head end to end (SPEC.md 7.6): the 1.6 stream that carries it, the decoder's
// renderer against the trainer's on the same field, the work the decoder charges for it, the
// checkpoint that keeps it. (Its gradients and training:
// tests/trainer/model/volume_render_test.cc.)
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "decoder/ray_marcher.h"
#include "decoder/render_work.h"
#include "encoder/scene_encoder.h"
#include "tests/common/decode_or_die.h"
#include "tests/common/renderer_agreement.h"
#include "tests/common/small_model.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/coded_model.h"
#include "trainer/train/trainer.h"

namespace ecrf {
namespace trainer {
namespace {

TensorfModel SmallDeferredModel(uint64_t seed) {
  TensorfConfig c = testing_models::SmallTensorfConfig();
  c.head.kind = HeadKind::kDeferred;
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

TEST(DeferredHead, CheckpointKeepsTheHead) {
  TensorfModel model = SmallDeferredModel(8);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("ecrf_deferred_ckpt_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "model.ckpt").string();
  SaveModelCheckpoint(path, model, 3, TrainOptions());
  const TensorfModel back = LoadModelFromCheckpoint(path);
  EXPECT_EQ(back.config().head.kind, HeadKind::kDeferred);
  EXPECT_EQ(back.head().params(), model.head().params());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
