// libFuzzer target: the container reader must return an error or walk the chunks, never crash.
//   cmake -S . -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DECRF_FUZZ=ON -DECRF_BUILD_TRAINER=OFF
//   build-fuzz/tests/fuzz/fuzz_container -max_total_time=60
#include <cstddef>
#include <cstdint>

#include "format/container.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  ecrf::ContainerReader reader;
  if (!reader.Open(data, size).ok()) return 0;
  for (;;) {
    ecrf::ChunkView chunk;
    bool done = false;
    if (!reader.Next(&chunk, &done).ok() || done) return 0;
    // Touch the payload so an out-of-bounds view would be caught by ASan.
    volatile uint8_t sum = 0;
    for (uint32_t i = 0; i < chunk.size; ++i) sum = uint8_t(sum + chunk.data[i]);
  }
}
