// The split every captured procedural sequence shares: frames 0, 8, 16, ... are "test" and "val"
// (the same views), the rest "train", in order, named "<scene>/frame_NNN".
#ifndef ECRF_TESTS_COMMON_HELD_OUT_FRAMES_H_
#define ECRF_TESTS_COMMON_HELD_OUT_FRAMES_H_

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "trainer/data/dataset.h"

namespace ecrf::trainer {

inline void ExpectEveryEighthFrameHeldOut(const Dataset& train, const Dataset& test,
                                          const Dataset& val, int frames,
                                          const std::string& scene) {
  const size_t held_out = size_t(frames + 7) / 8;
  ASSERT_EQ(test.views.size(), held_out);
  EXPECT_EQ(train.views.size(), size_t(frames) - held_out);
  ASSERT_EQ(val.views.size(), test.views.size());
  for (size_t k = 0; k < test.views.size(); ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "%s/frame_%03zu", scene.c_str(), 8 * k);
    EXPECT_EQ(test.views[k].name, name);
    EXPECT_EQ(val.views[k].rgb.pixels, test.views[k].rgb.pixels);
  }
  size_t t = 0;
  for (int i = 0; i < frames; ++i) {
    if (i % 8 == 0) continue;
    char name[64];
    std::snprintf(name, sizeof name, "%s/frame_%03d", scene.c_str(), i);
    ASSERT_LT(t, train.views.size());
    EXPECT_EQ(train.views[t++].name, name);
  }
}

}  // namespace ecrf::trainer

#endif  // ECRF_TESTS_COMMON_HELD_OUT_FRAMES_H_
