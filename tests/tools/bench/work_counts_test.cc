#include "tools/bench/work_counts.h"

#include <gtest/gtest.h>

#include "tests/common/small_model.h"

namespace ecrf {
namespace tools {
namespace {

// A dense layer's forward is one multiply-add per weight and row: the forward count is twice the
// head's parameters less its biases, whatever the layer shapes.
TEST(WorkCounts, HeadForwardIsTwoFlopsPerWeightAndRow) {
  for (int layers : {1, 2}) {
    const trainer::TensorfModel model = testing_models::DenseSmallModel(layers);
    const trainer::AppearanceHead& head = model.head();
    const trainer::AppearanceHeadConfig& c = head.config();
    const double biases = c.hidden * layers + 3.0;
    const double weights = double(head.num_params()) - biases;
    const MlpFlops f = HeadFlops(c, head, 10);
    EXPECT_DOUBLE_EQ(f.forward, 2.0 * 10 * weights) << layers << " hidden layers";
    // The backward takes every weight's gradient and the inputs' below the view encoding.
    EXPECT_GT(f.backward, f.forward);
    EXPECT_LT(f.backward, 2.0 * f.forward);
  }
}

TEST(WorkCounts, ScatterCountsSixCornersPerComponent) {
  // 2 density samples over 3 + 3 + 2 components, 1 appearance sample over 4 + 4 + 4.
  const ScatterWork w = ScatterCounts(2, 8, 1, 12);
  const double entries = 6.0 * (2 * 8 + 1 * 12);
  EXPECT_DOUBLE_EQ(w.flops, 2.0 * entries);
  EXPECT_DOUBLE_EQ(w.bytes, 8.0 * entries);
  EXPECT_DOUBLE_EQ(ScatterCounts(0, 8, 0, 12).flops, 0.0);
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
