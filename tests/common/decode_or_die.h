// Decodes a stream a test made itself with the embeddable decoder; a decoding error fails the test.
#ifndef ECRF_TESTS_COMMON_DECODE_OR_DIE_H_
#define ECRF_TESTS_COMMON_DECODE_OR_DIE_H_

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "decoder/scene_decoder.h"

namespace ecrf {

inline dec::SceneField DecodeOrDie(const std::vector<uint8_t>& bytes) {
  dec::SceneField field;
  const Status s =
      dec::DecodeScene(bytes.data(), bytes.size(), dec::DecodeOptions(), &field, nullptr);
  EXPECT_TRUE(s.ok()) << s.message();
  return field;
}

}  // namespace ecrf

#endif  // ECRF_TESTS_COMMON_DECODE_OR_DIE_H_
