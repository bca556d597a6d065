// libFuzzer target: any byte string that decodes renders a small view with defined pixels only.
// The first byte picks the grid storage (float32 or int16) and the camera; the rest is the stream.
// A scene that decodes must render without crashing, within the decoder's default budgets, and
// every output value must be finite and in [0, 1] (SPEC.md 7.2, 1.2). Seed with tests/conformance.
// The budgets bound every execution: decode work (2^20 + 64 per byte, fuzz_scene_decoder.cc), 64
// MiB of memory, 4096
// samples per ray and the default render work budget (30 pixels x 6 M multiply-adds, ~10 ms), so
// an execution that runs past libFuzzer's -timeout (scripts/fuzz.sh: 10 s) is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "decoder/camera.h"
#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint8_t mode = data[0];
  ecrf::dec::DecodeOptions options;
  options.storage = (mode & 1) ? ecrf::dec::GridStorage::kInt16 : ecrf::dec::GridStorage::kFloat32;
  options.max_memory_bytes = uint64_t{64} << 20;  // keep each execution small
  options.work_base = uint64_t{1} << 20;
  options.work_per_byte = 64;
  ecrf::dec::SceneField scene;
  if (!ecrf::dec::DecodeScene(data + 1, size - 1, options, &scene, nullptr).ok()) return 0;
  ecrf::dec::RenderOptions render;
  render.sample_budget = 4096;
  render.work_budget = ecrf::dec::kDefaultWorkBudget;
  render.early_stop_transmittance = (mode & 2) ? 0.f : 1e-4f;
  render.skip_empty_space = (mode & 4) == 0;
  ecrf::dec::RayMarcher marcher;
  if (!marcher.Init(&scene, render).ok()) return 0;
  const ecrf::dec::Camera cam = ecrf::dec::OrbitCamera(6, 5, 0.25f * (mode >> 3), 0.4f, 3.5f);
  uint8_t rgba[6 * 5 * 4];
  float rgb[6 * 5 * 3];
  if (!marcher.RenderImage(cam, rgba, rgb).ok()) return 0;
  for (float v : rgb) {
    if (!(v >= 0.f && v <= 1.f)) __builtin_trap();
  }
  return 0;
}
