// Quantization-aware training: the grids it renders are the ones the decoder reconstructs, the
// straight-through step is exactly a training step on those grids with its gradient handed to
// the float grids, and the float grids come back untouched.
#include "trainer/rate/quant_aware.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "decoder/scene_decoder.h"
#include "encoder/coef_quantizer.h"
#include "encoder/scene_encoder.h"
#include "format/coefficients/int_idct.h"
#include "format/container.h"
#include "format/mlp_coder.h"
#include "tests/common/small_model.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/coded_model.h"
#include "trainer/train/rate_state.h"

namespace ecrf {
namespace trainer {
namespace {

TensorfModel SmallModel(uint64_t seed) {
  TensorfModel model(testing_models::SmallTensorfConfig());
  model.Initialize({21, 18, 13}, seed);
  return model;
}

encoder::RateConfig SmallBlocks() { return testing_models::SmallRateBlocks(); }

// With rounding to nearest, with a dead zone (rounding offset 0.3) and with RDOQ
// (encoder/coef_rdoq.h): training sees the file.
class QuantAwareOffset : public ::testing::TestWithParam<std::pair<float, float>> {};

TEST_P(QuantAwareOffset, ReconstructionIsWhatTheDecoderDecodes) {
  const float offset = GetParam().first, rdoq = GetParam().second;
  const TensorfModel model = SmallModel(3);
  const encoder::RateConfig blocks = SmallBlocks();
  // Coarser than the 8-bit peak step, as --quant-step-scale 3 trains.
  std::vector<float> steps = ChooseQuantSteps(model, blocks, 8);
  for (float& s : steps) s *= 3.f;
  encoder::EncodeOptions o;
  o.blocks = blocks;
  o.steps = steps;
  o.rounding_offset = offset;
  o.rdoq_lambda = rdoq;
  o.drop_zero_components = false;
  const std::vector<uint8_t> bytes = EncodeScene(model, o);
  dec::SceneField field;
  const Status status =
      dec::DecodeScene(bytes.data(), bytes.size(), dec::DecodeOptions(), &field, nullptr);
  ASSERT_TRUE(status.ok()) << status.message();

  const VmGrid* grids[2] = {&model.density(), &model.appearance()};
  const dec::VmGrid* decoded[2] = {&field.density, &field.appearance};
  double worst_units = 0.0, worst_steps = 0.0;
  for (int g = 0; g < 2; ++g) {
    std::vector<float> q;
    ReconstructQuantizedGrid(*grids[g], steps.data() + 6 * g, blocks, &q, offset, rdoq);
    ASSERT_EQ(q.size(), grids[g]->params().size());
    for (int t = 0; t < 6; ++t) {
      const float* mine = q.data() + (RateTensorData(*grids[g], t) - grids[g]->params().data());
      const float* theirs =
          t < 3 ? decoded[g]->plane_f32[t].data() : decoded[g]->line_f32[t - 3].data();
      const float* original = RateTensorData(*grids[g], t);
      const size_t n = t < 3 ? grids[g]->plane_size(t) : grids[g]->line_size(t - 3);
      const double step = steps[6 * g + t];
      const double unit = std::ldexp(step, -IdctOutputFracBits(8));
      for (size_t i = 0; i < n; ++i) {
        worst_units = std::max(worst_units, std::fabs(double(mine[i]) - theirs[i]) / unit);
        worst_steps = std::max(worst_steps, std::fabs(double(mine[i]) - original[i]) / step);
      }
    }
  }
  // The integer IDCT is the float one up to its final rounding (one output unit).
  EXPECT_LT(worst_units, 1.05);
  // And the reconstruction did quantize: the coarse steps move values by a visible fraction.
  EXPECT_GT(worst_steps, 0.1);
}

INSTANTIATE_TEST_SUITE_P(Offsets, QuantAwareOffset,
                         ::testing::Values(std::make_pair(0.5f, 0.f), std::make_pair(0.3f, 0.f),
                                           std::make_pair(0.5f, 0.3f)));

// RDOQ in the encoder: a smaller file than rounding, larger lambdas smaller still, and the
// lambda is checked.
TEST(CoefRdoq, EncodedSceneShrinksWithLambda) {
  const TensorfModel model = SmallModel(4);
  encoder::EncodeOptions o;
  o.blocks = SmallBlocks();
  o.steps = ChooseQuantSteps(model, o.blocks, 8);
  for (float& s : o.steps) s *= 3.f;
  size_t previous = EncodeScene(model, o).size();
  for (float lambda : {0.1f, 0.5f, 2.f}) {
    o.rdoq_lambda = lambda;
    const size_t bytes = EncodeScene(model, o).size();
    EXPECT_LT(bytes, previous) << lambda;
    previous = bytes;
  }
  for (float bad : {-0.1f, 11.f}) {
    o.rdoq_lambda = bad;
    EXPECT_THROW(EncodeScene(model, o), std::invalid_argument) << bad;
  }
}

// Rounding to nearest is std::round to the bit (half away from zero), written without it: on
// halves, on the doubles either side of them, on huge and tiny values, signed zeros, infinities
// and NaN, and on a million random quotients.
TEST(CoefQuantizer, RoundingIsStdRound) {
  std::vector<double> values = {0.0,
                                -0.0,
                                0.5,
                                -0.5,
                                1.5,
                                -2.5,
                                4503599627370495.5,
                                4503599627370497.0,
                                1e300,
                                -1e300,
                                5e-324,
                                std::numeric_limits<double>::infinity(),
                                -std::numeric_limits<double>::infinity()};
  for (double h = 0.5; h < 1e6; h = h * 3 + 0.5) {
    values.push_back(std::nextafter(h, 0.0));
    values.push_back(std::nextafter(h, 1e9));
    values.push_back(-std::nextafter(h, 0.0));
  }
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-300.0, 300.0);
  for (int i = 0; i < 1000000; ++i) values.push_back(u(rng));
  for (double v : values) {
    const double got = encoder::QuantizeLevel(v, 1.0, 0.5), want = std::round(v);
    ASSERT_EQ(std::signbit(got), std::signbit(want)) << v;
    ASSERT_EQ(got, want) << v;
  }
  EXPECT_TRUE(std::isnan(encoder::QuantizeLevel(std::nan(""), 1.0, 0.5)));
  EXPECT_EQ(encoder::QuantizeLevel(7.5, 2.5, 0.5), 3.0);
}

// The dead zone: levels move toward zero by 0.5 - offset, so the file shrinks.
TEST(CoefQuantizer, OffsetWidensTheDeadZone) {
  for (double v : {-2.5, -1.7, -0.5, -0.49, 0.0, 0.3, 0.5, 0.69, 0.71, 1.5, 126.6}) {
    EXPECT_EQ(encoder::QuantizeLevel(v, 1.0, 0.5), std::round(v)) << v;
  }
  EXPECT_EQ(encoder::QuantizeLevel(0.69, 1.0, 0.3), 0.0);
  EXPECT_EQ(encoder::QuantizeLevel(0.71, 1.0, 0.3), 1.0);
  EXPECT_EQ(encoder::QuantizeLevel(-0.71, 1.0, 0.3), -1.0);
  EXPECT_EQ(encoder::QuantizeLevel(-1.69, 1.0, 0.3), -1.0);
  EXPECT_EQ(encoder::QuantizeLevel(3.4, 2.0, 0.3), 2.0);  // 1.7 + 0.3
  EXPECT_EQ(encoder::QuantizeLevel(0.49999999999999994, 1.0, 0.5),
            0.0);  // as std::round, not floor(x + 0.5)

  const TensorfModel model = SmallModel(4);
  encoder::EncodeOptions o;
  o.blocks = SmallBlocks();
  const size_t nearest = EncodeScene(model, o).size();
  o.rounding_offset = 0.25f;
  EXPECT_LT(EncodeScene(model, o).size(), nearest);
  for (float bad : {0.f, -0.1f, 0.6f}) {
    o.rounding_offset = bad;
    EXPECT_THROW(EncodeScene(model, o), std::invalid_argument) << bad;
  }
}

struct Batch {
  int n = 64;
  std::vector<float> o, d, rgb;
};

Batch MakeBatch() {
  Batch b;
  std::mt19937 rng(11);
  std::normal_distribution<float> nd;
  std::uniform_real_distribution<float> u(0.1f, 0.9f);
  for (int i = 0; i < b.n; ++i) {
    float p[3] = {nd(rng), nd(rng), nd(rng)};
    const float len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (int a = 0; a < 3; ++a) b.o.push_back(3.f * p[a] / len);
    for (int a = 0; a < 3; ++a) b.d.push_back(-p[a] / len);
    for (int a = 0; a < 3; ++a) b.rgb.push_back(u(rng));
  }
  return b;
}

// mlp_levels 7: the head is quantized too (coarsely, so that it matters).
TEST(QuantAware, StraightThroughStepIsTheStepOnTheDecodedModel) {
  const int mlp_levels = 7;
  TensorfModel model = SmallModel(5);
  const encoder::RateConfig blocks = SmallBlocks();
  std::vector<float> steps = ChooseQuantSteps(model, blocks, 8);
  for (float& s : steps) s *= 30.f;  // coarse: about 4 levels per tensor
  const Batch b = MakeBatch();

  // Reference: a model whose grids are replaced by their reconstruction.
  TensorfModel decoded = model;
  ReconstructQuantizedGrid(model.density(), steps.data(), blocks, &decoded.density().params());
  ReconstructQuantizedGrid(model.appearance(), steps.data() + 6, blocks,
                           &decoded.appearance().params());
  ReconstructQuantizedHead(model, mlp_levels, &decoded.head().params());
  decoded.ZeroGrads();
  const TrainStepStats want = TrainStep(decoded, b.n, b.o.data(), b.d.data(), b.rgb.data(), 17);

  const std::vector<float> density_before = model.density().params();
  const std::vector<float> appearance_before = model.appearance().params();
  const std::vector<float> head_before = model.head().params();
  QuantAwareModel qat;
  qat.Refresh(model, steps, blocks, mlp_levels);
  model.ZeroGrads();
  qat.Apply(&model);
  const TrainStepStats got = TrainStep(model, b.n, b.o.data(), b.d.data(), b.rgb.data(), 17);
  qat.Restore(&model);

  EXPECT_GT(want.density_samples, 100);
  // G + (Q(G) - G) rounds to Q(G) or its float neighbour; the losses agree to float precision.
  EXPECT_NEAR(got.loss, want.loss, 1e-6 * want.loss);
  EXPECT_EQ(got.density_samples, want.density_samples);
  // The loss differs from the float model's: the test exercises real quantization.
  TensorfModel float_model = model;
  const TrainStepStats plain =
      TrainStep(float_model, b.n, b.o.data(), b.d.data(), b.rgb.data(), 17);
  EXPECT_GT(std::fabs(plain.loss - want.loss), 1e-4 * want.loss);

  auto max_rel = [](const std::vector<float>& a, const std::vector<float>& b) {
    double worst = 0.0, scale = 1e-12;
    for (size_t i = 0; i < a.size(); ++i) {
      worst = std::max(worst, std::fabs(double(a[i]) - b[i]));
      scale = std::max(scale, std::fabs(double(b[i])));
    }
    return worst / scale;
  };
  EXPECT_LT(max_rel(model.density().grads(), decoded.density().grads()), 1e-4);
  EXPECT_LT(max_rel(model.appearance().grads(), decoded.appearance().grads()), 1e-4);
  EXPECT_LT(max_rel(model.head().grads(), decoded.head().grads()), 1e-4);
  // The float grids are back, bit for bit.
  EXPECT_EQ(model.density().params(), density_before);
  EXPECT_EQ(model.appearance().params(), appearance_before);
  EXPECT_EQ(model.head().params(), head_before);
}

// The head as the decoder reads it back from the MLPW chunk the encoder writes.
TEST(QuantAware, HeadReconstructionIsWhatTheDecoderDecodes) {
  const TensorfModel model = SmallModel(9);
  std::vector<float> q;
  ReconstructQuantizedHead(model, 15, &q);
  ASSERT_EQ(q.size(), model.head().params().size());
  // The MLPW chunk the encoder writes, decoded by the format's decoder with the stream's layout.
  encoder::EncodeOptions o;
  o.mlp_max_level = 15;
  o.drop_zero_components = false;
  const std::vector<uint8_t> bytes = EncodeScene(model, o);
  ContainerReader reader;
  ASSERT_TRUE(reader.Open(bytes.data(), bytes.size()).ok());
  ChunkView chunk;
  bool done = false;
  std::vector<float> decoded;
  while (!done) {
    ASSERT_TRUE(reader.Next(&chunk, &done).ok());
    if (chunk.type != FourCC("MLPW")) continue;
    const MlpLayout layout = HeadMlpLayout(model.config().head);
    decoded.resize(MlpParamCount(layout));
    ASSERT_EQ(chunk.data[0], kMlpPrecisionQuantized);
    ASSERT_TRUE(DecodeQuantizedMlp(layout, chunk.data + 4, chunk.size - 4, decoded.data()).ok());
  }
  ASSERT_EQ(decoded.size(), q.size());
  size_t moved = 0;
  for (size_t i = 0; i < q.size(); ++i) {
    ASSERT_EQ(q[i], decoded[i]) << "parameter " << i;
    moved += q[i] != model.head().params()[i];
  }
  EXPECT_GT(moved, q.size() / 2);
}

TEST(QuantAware, ApplyNeedsAFreshRefresh) {
  TensorfModel model = SmallModel(6);
  QuantAwareModel qat;
  EXPECT_FALSE(qat.fresh_for(model));
  EXPECT_THROW(qat.Apply(&model), std::logic_error);
  const encoder::RateConfig blocks = SmallBlocks();
  qat.Refresh(model, ChooseQuantSteps(model, blocks, 8), blocks);
  EXPECT_TRUE(qat.fresh_for(model));
  model.UpsampleTo({25, 20, 15});  // a new shape makes the stored error stale
  EXPECT_FALSE(qat.fresh_for(model));
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
