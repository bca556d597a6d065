// The tiny preset on the built-in procedural scene, shortened: the runs of the trainer's tests of
// events, checkpoints and stops, which are about state rather than quality.
#ifndef ECRF_TESTS_COMMON_TINY_RUN_H_
#define ECRF_TESTS_COMMON_TINY_RUN_H_

#include "trainer/train/train_options.h"

namespace ecrf {
namespace testing_runs {

// size x size pixels, `views` training views, `iters` iterations, one scored test view and no
// progress lines.
inline trainer::TrainOptions TinyBuiltinRun(int size, int views, int iters) {
  trainer::TrainOptions o = trainer::PresetOptions("tiny");
  o.procedural_scene = trainer::ProceduralScene::kBuiltin;
  o.builtin_size = size;
  o.builtin_views = views;
  o.iters = iters;
  o.max_test_views = 1;
  o.progress_every = 1000;
  return o;
}

}  // namespace testing_runs
}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_TINY_RUN_H_
