// libFuzzer target: coefficient decoding of arbitrary bytes, for every block shape family, must
// end in an error status or valid coefficients within the bound, never a crash or a hang.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "format/coefficients/coef_coder.h"
#include "format/coefficients/int_idct.h"
#include "format/entropy/range_coder.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  // First byte picks the shape (mod 5), the context set and the bit depth; the rest is the coded
  // stream.
  static const ecrf::BlockShape kShapes[] = {
      {16, 16, 16}, {1, 8, 8}, {1, 1, 32}, {32, 4, 32}, {1, 1, 1}};
  const ecrf::BlockShape shape = kShapes[data[0] % 5];
  const bool wide = data[0] & 0x80;
  const int32_t max_abs = wide ? 32767 : 127;
  // Bits 6 and 5: narrow, wide or neighbour (the last on a 2 x 3 x 4 grid, so that the 64
  // blocks wrap around it).
  const int set_bits = (data[0] >> 5) & 3;
  const ecrf::CoefContextSet set = set_bits == 0   ? ecrf::CoefContextSet::kNarrow
                                   : set_bits == 1 ? ecrf::CoefContextSet::kWide
                                                   : ecrf::CoefContextSet::kNeighbour;
  const int grid[3] = {2, 3, 4};
  ecrf::CoefContexts contexts;
  if (!contexts.Init(shape, set, grid, size_t{1} << 26).ok()) return 0;
  ecrf::RangeDecoder decoder(data + 1, size - 1);
  std::vector<int32_t> coeffs(shape.Volume()), samples(shape.Volume());
  const int dims[3] = {shape.n0, shape.n1, shape.n2};
  for (int block = 0; block < 64; ++block) {
    if (!ecrf::DecodeCoefBlock(decoder, contexts, max_abs, coeffs.data()).ok()) return 0;
    for (int32_t c : coeffs) {
      if (std::abs(c) > max_abs) std::abort();  // the decoder promised the bound
    }
    ecrf::InverseDctInt(coeffs.data(), dims, wide ? 16 : 8, samples.data());
  }
  // Finish's end-of-stream arithmetic runs under the sanitizers like the rest; a fuzzer counts
  // crashes, not rejected streams, so its verdict does not matter here.
  (void)decoder.Finish();
  return 0;
}
