#include "trainer/train/eval_progress.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "trainer/data/camera.h"
#include "trainer/data/dataset.h"
#include "trainer/scenes/builtin_scene.h"

namespace ecrf {
namespace trainer {
namespace {

TEST(EvalProgress, CountsTheViewsAStrideAndBudgetLeave) {
  EXPECT_EQ(EvalViewCount(200, 10, 0), 20);
  EXPECT_EQ(EvalViewCount(201, 10, 0), 21);  // views 0, 10, ..., 200
  EXPECT_EQ(EvalViewCount(8, 1, 3), 3);
  EXPECT_EQ(EvalViewCount(8, 0, 0), 8);  // a stride below 1 is 1, as the evaluators treat it
  EXPECT_EQ(EvalViewCount(0, 4, 2), 0);
  // Which views, in order: the same rule picks the held-out cameras that are aligned.
  EXPECT_EQ(EvalViews(201, 10, 3), (std::vector<size_t>{0, 10, 20}));
  EXPECT_EQ(EvalViews(7, 3, 0), (std::vector<size_t>{0, 3, 6}));
  EXPECT_EQ(EvalViews(3, 0, 0), (std::vector<size_t>{0, 1, 2}));
}

TEST(EvalProgress, LineStatesViewsTimePerViewAndWhatIsLeft) {
  EvalProgress progress("evaluating", 8, 1e9);
  EXPECT_EQ(progress.Line(2, 30.0, ""), "evaluating: view 2/8, 15.0 s/view, 90 s left");
  EXPECT_EQ(progress.Line(8, 8.0, "3.0 samples per ray"),
            "evaluating: view 8/8, 1.0 s/view, 0 s left, 3.0 samples per ray");
}

TEST(DownscaleViews, ShrinksImagesAndCamerasTogether) {
  const Dataset full = MakeBuiltinScene("test", 48, 40, 4, 7);
  const Dataset half = DownscaleViews(full, 2);
  ASSERT_EQ(half.views.size(), full.views.size());
  for (size_t v = 0; v < full.views.size(); ++v) {
    EXPECT_EQ(half.views[v].rgb.width, 24);
    EXPECT_EQ(half.views[v].rgb.height, 20);
    const Camera expected = ScaledCamera(full.views[v].camera, 2);
    EXPECT_EQ(half.views[v].camera.width, expected.width);
    EXPECT_DOUBLE_EQ(half.views[v].camera.fx, expected.fx);
    EXPECT_DOUBLE_EQ(half.views[v].camera.cy, expected.cy);
    // Area filter: the mean colour of the image is kept.
    double sum_full = 0, sum_half = 0;
    for (float p : full.views[v].rgb.pixels) sum_full += p;
    for (float p : half.views[v].rgb.pixels) sum_half += p;
    EXPECT_NEAR(sum_half * 4.0, sum_full, 1e-3 * sum_full);
  }
  EXPECT_EQ(DownscaleViews(full, 1).views[0].rgb.pixels, full.views[0].rgb.pixels);
  EXPECT_THROW(DownscaleViews(full, 0), std::invalid_argument);
  EXPECT_THROW(DownscaleViews(full, 64), std::invalid_argument);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
