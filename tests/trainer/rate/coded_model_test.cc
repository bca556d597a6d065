// DescribeModel: the trainer's model in the encoder's terms (trainer/rate/coded_model.h). Every
// tensor, the head and the mask are the model's own values; an unbounded scene's HEAD box is its
// region of interest (the grids span the contracted cube).
#include "trainer/rate/coded_model.h"

#include <gtest/gtest.h>

#include <vector>

#include "tests/common/small_model.h"

namespace ecrf {
namespace trainer {
namespace {

TEST(CodedModel, DescribesEveryTensorTheHeadAndTheMask) {
  TensorfModel model(testing_models::SmallTensorfConfig());
  model.Initialize({9, 8, 7}, 3);
  model.SetAlphaMask(AlphaMask(model.aabb(), {3, 2, 2}, {1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}));
  const encoder::SceneDescription s = DescribeModel(model);
  const VmGrid* grids[2] = {&model.density(), &model.appearance()};
  for (int g = 0; g < 2; ++g) {
    for (int t = 0; t < 6; ++t) {
      EXPECT_EQ(s.header.ranks[g][t % 3], grids[g]->ranks()[t % 3]);
      const float* data = RateTensorData(*grids[g], t);
      const size_t size = RateTensorLayout(*grids[g], t, encoder::RateConfig()).tensor_size();
      EXPECT_EQ(s.tensors[g][t], std::vector<float>(data, data + size)) << g << " " << t;
    }
  }
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(s.header.res[a], model.res()[a]);
    EXPECT_EQ(s.header.aabb_min[a], model.aabb().min[a]);
  }
  EXPECT_EQ(s.header.step_size, model.step_size());
  EXPECT_EQ(s.head_params, model.head().params());
  ASSERT_TRUE(s.mask.has_value());
  EXPECT_EQ(s.mask->res, (std::array<int, 3>{3, 2, 2}));
  EXPECT_EQ(s.mask->occupancy, model.alpha_mask()->occupancy());

  model.ClearAlphaMask();
  EXPECT_FALSE(DescribeModel(model).mask.has_value());
}

TEST(CodedModel, AnUnboundedSceneIsDescribedByItsRegionOfInterest) {
  TensorfConfig c = testing_models::SmallTensorfConfig();
  c.scene_model = SceneModel::kUnbounded;
  c.aabb.min = {-2.f, -2.f, -2.f};
  c.aabb.max = {2.f, 2.f, 2.f};
  c.roi.min = {-5.f, -4.f, -3.f};
  c.roi.max = {5.f, 4.f, 3.f};
  TensorfModel model(c);
  model.Initialize({8, 8, 8}, 4);
  const encoder::SceneDescription s = DescribeModel(model);
  EXPECT_EQ(s.header.scene_model, uint8_t(SceneModel::kUnbounded));
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(s.header.aabb_min[a], c.roi.min[a]);
    EXPECT_EQ(s.header.aabb_max[a], c.roi.max[a]);
  }
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
