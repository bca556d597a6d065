// libFuzzer target: decoding any byte string gives a valid scene or an error, never a crash, a
// leak or an allocation beyond the decoder limits. A decode work budget of 2^20 + 64 units per
// byte (1/16 of the default; trained streams cost 14-110) keeps every execution under a second
// with the sanitizers, so a -timeout (10 s in scripts/fuzz.sh) is a finding, and still lets the
// conformance streams decode. Seed it with tests/conformance/*.ecrf:
//   build-fuzz/tests/fuzz/fuzz_scene_decoder -max_total_time=60 -rss_limit_mb=4096 corpus/
#include <cstddef>
#include <cstdint>

#include "decoder/scene_decoder.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  ecrf::dec::SceneField scene;
  ecrf::dec::SceneInfo info;
  ecrf::dec::DecodeOptions options;
  options.work_base = uint64_t{1} << 20;
  options.work_per_byte = 64;
  const ecrf::Status s = ecrf::dec::DecodeScene(data, size, options, &scene, &info);
  if (s.ok() && !scene.Validate().ok()) __builtin_trap();
  return 0;
}
