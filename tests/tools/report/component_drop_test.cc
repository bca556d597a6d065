// `ecrf report components`: each component's drop test reads what the encoder saves and what the
// decoded model loses; lambda_e decides which go; the file without them is what it says.
#include "tools/report/component_drop.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "ecrf/decoder.h"
#include "tests/common/small_model.h"
#include "tools/report/quant_sensitivity.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/quant_aware.h"

namespace ecrf {
namespace tools {
namespace {

trainer::TensorfModel SmallModel() { return testing_models::DenseSmallModel(); }

encoder::EncodeOptions Options() {
  encoder::EncodeOptions o;
  o.blocks = testing_models::SmallRateBlocks();
  o.steps = trainer::ChooseQuantSteps(SmallModel(), o.blocks, 8);
  for (float& s : o.steps) s *= 2.f;
  o.mlp_max_level = 7;
  return o;
}

struct Rays {
  int n = 1024;
  std::vector<float> origins, dirs, rgb;
};

// Targets: the decoded model's own colours, so the decoded model is at its optimum.
const Rays& TheRays() {
  static const Rays rays = [] {
    Rays r;
    testing_models::RaysFromSphere(r.n, 11, &r.origins, &r.dirs);
    r.rgb.resize(static_cast<size_t>(r.n) * 3);
    const encoder::EncodeOptions o = Options();
    trainer::RenderRays(DecodedModel(SmallModel(), o.steps, o.blocks, o.mlp_max_level), r.n,
                        r.origins.data(), r.dirs.data(), r.rgb.data(), nullptr);
    return r;
  }();
  return rays;
}

ComponentReport Measure(const trainer::TensorfModel& model, double lambda_e) {
  const Rays& r = TheRays();
  return MeasureComponentCosts(model, Options(), lambda_e, r.n, r.origins.data(), r.dirs.data(),
                               r.rgb.data());
}

int CodedRanks(const std::vector<uint8_t>& file) {
  ecrf_scene* scene = ecrf_scene_create();
  EXPECT_EQ(ecrf_scene_decode(scene, file.data(), file.size(), ECRF_STORAGE_FLOAT32), 0);
  ecrf_scene_info info;
  EXPECT_EQ(ecrf_scene_get_info(scene, &info), 0);
  ecrf_scene_destroy(scene);
  int total = 0;
  for (int m = 0; m < 3; ++m) total += info.density_ranks[m] + info.appearance_ranks[m];
  return total;
}

TEST(ComponentDrop, EveryComponentIsTestedAndNothingGoesWhenBitsAreFree) {
  const ComponentReport r = Measure(SmallModel(), 0.0);
  ASSERT_EQ(r.components.size(), 24u);
  EXPECT_NEAR(r.mse, 0.0, 1e-12);  // the targets are the decoded model's colours
  for (const ComponentCost& c : r.components) {
    EXPECT_GT(c.saved_bytes, 0) << c.grid << " " << c.mode << " " << c.component;
    EXPECT_GE(c.dmse, 0.0);
    EXPECT_FALSE(c.drop);
  }
  EXPECT_EQ(r.dropped, 0);
  EXPECT_EQ(r.bytes_after, r.bytes);
  EXPECT_EQ(r.mse_after, r.mse);
  EXPECT_EQ(CodedRanks(r.file_after), 24);
}

TEST(ComponentDrop, LambdaDecidesWhatGoesAndTheFileWithoutItIsMeasured) {
  // The price of a bit at which about half the components are worth less than their bits.
  const ComponentReport free_bits = Measure(SmallModel(), 0.0);
  std::vector<double> break_even;
  for (const ComponentCost& c : free_bits.components)
    break_even.push_back(c.dmse / (8.0 * double(c.saved_bytes)));
  std::sort(break_even.begin(), break_even.end());
  const double lambda = break_even[break_even.size() / 2];
  const ComponentReport half = Measure(SmallModel(), lambda);
  int marked = 0;
  for (size_t i = 0; i < half.components.size(); ++i) {
    const ComponentCost& c = half.components[i];
    // The same measurement whatever lambda_e; lambda_e only decides.
    EXPECT_EQ(c.saved_bytes, free_bits.components[i].saved_bytes);
    EXPECT_EQ(c.dmse, free_bits.components[i].dmse);
    EXPECT_EQ(c.drop, c.dmse < lambda * 8.0 * double(c.saved_bytes));
    marked += c.drop;
  }
  EXPECT_EQ(marked, 12);
  EXPECT_EQ(half.dropped, 12);
  // The file without them: smaller, 12 components fewer in the stream, a worse decoded model.
  EXPECT_LT(half.bytes_after, half.bytes);
  EXPECT_EQ(CodedRanks(half.file_after), 24 - 12);
  EXPECT_GT(half.mse_after, half.mse);
  // A higher price of bits drops more, and the file loses more.
  const ComponentReport dear = Measure(SmallModel(), break_even.back() * 2.0);
  EXPECT_EQ(dear.dropped, 24);
  EXPECT_LT(dear.bytes_after, half.bytes_after);
  EXPECT_GT(dear.mse_after, half.mse_after);
  // A component already zero is not in the stream: dropping it saves nothing and is not marked.
  trainer::TensorfModel zeroed = SmallModel();
  ZeroComponent(&zeroed, 0, 2, 1);
  const ComponentReport z = Measure(zeroed, lambda);
  for (const ComponentCost& c : z.components) {
    if (c.grid == 0 && c.mode == 2 && c.component == 1) {
      EXPECT_EQ(c.saved_bytes, 0);
      EXPECT_FALSE(c.drop);
    }
  }
  EXPECT_THROW(ZeroComponent(&zeroed, 0, 2, 4), std::invalid_argument);
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
