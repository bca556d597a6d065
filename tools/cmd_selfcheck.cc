// `ecrf selfcheck`: a quick end-to-end check of the normative pieces on this machine: the
// coefficient coder round-trips random sparse blocks, the integer IDCT stays within one output
// unit of float64, and the container detects damage. Exit code 0 only if everything passes.
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "format/coefficients/coef_coder.h"
#include "format/coefficients/float_dct.h"
#include "format/coefficients/int_idct.h"
#include "format/container.h"
#include "format/entropy/range_coder.h"
#include "tools/cli.h"
#include "tools/commands.h"

namespace ecrf {
namespace tools {
namespace {

bool CheckCoder(std::mt19937& rng) {
  const BlockShape shapes[] = {{16, 16, 16}, {1, 8, 8}, {4, 8, 32}};
  long coefficients = 0;
  size_t bytes = 0;
  for (const BlockShape& shape : shapes) {
    CoefContexts enc_ctx, dec_ctx;
    if (!enc_ctx.Init(shape).ok() || !dec_ctx.Init(shape).ok()) return false;
    const int volume = shape.Volume();
    const int blocks = 64;
    std::vector<int32_t> input(size_t(volume) * blocks, 0);
    std::uniform_real_distribution<double> u(0, 1);
    for (int b = 0; b < blocks; ++b) {
      if (u(rng) < 0.5) continue;  // half the blocks all zero
      for (int i = 0; i < volume; ++i) {
        const double scale = 8.0 / (1 + i / 16.0);
        const double m = std::min(127.0, std::floor(-scale * std::log(1 - u(rng))));
        input[size_t(b) * volume + i] = int32_t(u(rng) < 0.5 ? -m : m);
      }
    }
    RangeEncoder enc;
    for (int b = 0; b < blocks; ++b) EncodeCoefBlock(enc, enc_ctx, &input[size_t(b) * volume]);
    const std::vector<uint8_t> stream = enc.Finish();
    RangeDecoder dec(stream.data(), stream.size());
    std::vector<int32_t> out(volume);
    for (int b = 0; b < blocks; ++b) {
      if (!DecodeCoefBlock(dec, dec_ctx, 127, out.data()).ok()) return false;
      for (int i = 0; i < volume; ++i) {
        if (out[i] != input[size_t(b) * volume + i]) return false;
      }
    }
    if (!dec.Finish().ok()) return false;
    coefficients += long(volume) * blocks;
    bytes += stream.size();
  }
  std::printf(
      "  coefficient coder: %ld coefficients round-trip in %zu bytes (%.3f bits/coefficient)\n",
      coefficients, bytes, 8.0 * bytes / coefficients);
  return true;
}

bool CheckIdct(std::mt19937& rng) {
  const int shapes[][3] = {{16, 16, 16}, {1, 8, 8}, {1, 32, 32}, {32, 4, 8}};
  double worst = 0;
  for (const auto& dims : shapes) {
    const int volume = dims[0] * dims[1] * dims[2];
    for (int t = 0; t < 8; ++t) {
      std::vector<int32_t> q(volume);
      std::uniform_int_distribution<int> d(-127, 127);
      for (auto& v : q) v = d(rng);
      std::vector<double> ref(q.begin(), q.end());
      InverseDct(ref.data(), dims);
      std::vector<int32_t> out(volume);
      InverseDctInt(q.data(), dims, 8, out.data());
      for (int i = 0; i < volume; ++i) worst = std::max(worst, std::fabs(out[i] - ref[i] * 256.0));
    }
  }
  std::printf("  integer IDCT: max error %.3f output units against float64 (limit 1)\n", worst);
  return worst <= 1.0;
}

bool CheckContainer() {
  ContainerWriter w;
  const uint8_t payload[3] = {1, 2, 3};
  w.AddChunk(FourCC("TEST"), payload, 3);
  std::vector<uint8_t> file = w.Finish();
  file[kFileHeaderBytes + 9] ^= 0x40;
  ContainerReader r;
  ChunkView c;
  bool done = false;
  const bool detected = !r.Open(file.data(), file.size()).ok() || !r.Next(&c, &done).ok();
  std::printf("  container: a flipped payload bit is %s\n", detected ? "detected" : "NOT detected");
  return detected;
}

}  // namespace

int RunSelfCheck(int argc, char** argv) {
  auto app = MakeCommand(
      "selfcheck",
      "a quick end-to-end check of the normative pieces on this machine: the coefficient coder "
      "round-trips random sparse blocks, the integer IDCT stays within one output unit of "
      "float64, and the container detects damage (exit code 0 only if everything passes)");
  if (const int rc = ParseCommandLine(app.get(), argc, argv); rc >= 0) return rc;
  std::mt19937 rng(2024);
  std::printf("ecrf selfcheck\n");
  const bool ok = CheckCoder(rng) & CheckIdct(rng) & CheckContainer();
  std::printf("%s\n", ok ? "selfcheck passed" : "selfcheck FAILED");
  return ok ? 0 : 1;
}

}  // namespace tools
}  // namespace ecrf
