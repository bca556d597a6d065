// libFuzzer target: decoding any byte string gives a valid scene or an error, never a crash, a
// leak or an allocation beyond the decoder limits. Seed it with tests/conformance/*.ecrf:
//   build-fuzz/tests/fuzz/fuzz_scene_decoder -max_total_time=60 -rss_limit_mb=4096 corpus/
#include <cstddef>
#include <cstdint>

#include "decoder/scene_decoder.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  ecrf::dec::SceneField scene;
  ecrf::dec::SceneInfo info;
  const ecrf::Status s =
      ecrf::dec::DecodeScene(data, size, ecrf::dec::DecodeOptions(), &scene, &info);
  if (s.ok() && !scene.Validate().ok()) __builtin_trap();
  return 0;
}
