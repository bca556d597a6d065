// The work budget of a render (decoder/render_work.h) and the decode budget of a stream
// (SPEC.md 8) against the small streams that cost the most: conformance/costly_streams.h.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "conformance/costly_streams.h"
#include "decoder/camera.h"
#include "decoder/ray_marcher.h"
#include "decoder/render_work.h"
#include "decoder/scene_decoder.h"
#include "ecrf/decoder.h"

namespace ecrf {
namespace dec {
namespace {

using costly::BuildCostlyStream;
using costly::CostlyScene;

bool Contains(const std::string& s, const char* part) { return s.find(part) != std::string::npos; }

Camera FrontCamera(int size) { return OrbitCameraDegrees(size, size, 0.0, 0.0, 3.f); }

// The widest head the limits allow (F 256, H 1024, P 3072, 16 frequencies): 10.6 M multiply-adds
// per coloured sample. Before the work budget one pixel of it took 39 s.
TEST(WorkBudget, TheWidestHeadIsRefusedWhenTheSceneIsPrepared) {
  const std::vector<uint8_t> bytes = BuildCostlyStream(costly::WidestHead());
  ASSERT_FALSE(bytes.empty());
  EXPECT_LT(bytes.size(), 64u * 1024u);
  SceneField field;
  const Status d = DecodeScene(bytes.data(), bytes.size(), DecodeOptions(), &field, nullptr);
  ASSERT_TRUE(d.ok()) << d.message();
  const SampleCosts costs = SceneSampleCosts(field);
  EXPECT_GT(costs.color, 10000000u);

  RayMarcher marcher;
  const Status s = marcher.Init(&field, RenderOptions());
  EXPECT_EQ(s.code(), kErrLimit);
  const std::string m = s.message();
  const std::string budget = "work budget of " + std::to_string(kDefaultWorkBudget) + " per pixel";
  EXPECT_TRUE(Contains(m, "costs 10") && Contains(m, budget.c_str()) &&
              Contains(m, "--work-budget"))
      << m;

  // The same through the C API: ecrf_scene_check_render and ecrf_scene_render agree.
  ecrf_scene* scene = ecrf_scene_create();
  ASSERT_EQ(ecrf_scene_decode(scene, bytes.data(), bytes.size(), ECRF_STORAGE_FLOAT32), 0);
  ecrf_render_options o;
  ecrf_render_options_default(&o);
  EXPECT_EQ(o.work_budget, kDefaultWorkBudget);
  EXPECT_EQ(ecrf_scene_check_render(scene, &o), ECRF_ERR_LIMIT);
  EXPECT_TRUE(Contains(ecrf_scene_message(scene), "work budget")) << ecrf_scene_message(scene);
  const Camera cam = FrontCamera(1);
  ecrf_camera c;
  for (int k = 0; k < 12; ++k) c.c2w[k] = cam.c2w[k];
  c.fx = cam.fx;
  c.fy = cam.fy;
  c.cx = cam.cx;
  c.cy = cam.cy;
  c.width = c.height = 1;
  uint8_t rgba[4];
  EXPECT_EQ(ecrf_scene_render(scene, &c, &o, rgba, nullptr), ECRF_ERR_LIMIT);
  o.work_budget = 0;  // no limit: the user accepts the cost
  EXPECT_EQ(ecrf_scene_check_render(scene, &o), 0) << ecrf_scene_message(scene);
  o.work_budget = costs.position + costs.density + costs.color;  // exactly one sample's worth
  EXPECT_EQ(ecrf_scene_check_render(scene, &o), 0) << ecrf_scene_message(scene);
  ecrf_scene_destroy(scene);
}

// A head that passes the check (0.5 M multiply-adds per sample) with 16384 samples per ray, every
// one coloured: 8 G multiply-adds per ray. The view stops once it has spent its budget, whatever
// the thread count.
TEST(WorkBudget, AViewThatSpendsItsBudgetIsRefusedWhileRendering) {
  CostlyScene cs;
  cs.appearance_rank = 16;
  cs.feature_dim = 32;
  cs.hidden = 512;
  cs.pe_freqs = 4;
  const std::vector<uint8_t> bytes = BuildCostlyStream(cs);
  ASSERT_FALSE(bytes.empty());
  EXPECT_LT(bytes.size(), 64u * 1024u);
  SceneField field;
  ASSERT_TRUE(DecodeScene(bytes.data(), bytes.size(), DecodeOptions(), &field, nullptr).ok());
  const SampleCosts costs = SceneSampleCosts(field);
  const Camera cam = FrontCamera(16);
  for (int threads : {1, 2}) {
    RenderOptions o;
    o.num_threads = threads;
    o.work_budget = 5000000;  // keeps the test quick; the default behaves alike, 2.5x sooner
    RayMarcher marcher;
    ASSERT_TRUE(marcher.Init(&field, o).ok());
    std::vector<uint8_t> rgba(16 * 16 * 4);
    RenderStats stats;
    const Status s = marcher.RenderImage(cam, rgba.data(), nullptr, &stats);
    EXPECT_EQ(s.code(), kErrLimit) << threads;
    const std::string m = s.message();
    EXPECT_TRUE(Contains(m, "spent its work budget of 1280000000") &&
                Contains(m, "5000000 per pixel x 256 pixels") && Contains(m, "16384 samples"))
        << m;
    // It stopped within one share per thread (and one sample) past the budget.
    EXPECT_GE(stats.work, 1280000000u);
    EXPECT_LE(stats.work, 1280000000u + threads * (uint64_t{1} << 22) + costs.color +
                              costs.density + 16 * 16384);
    EXPECT_GT(stats.color_samples, 0u);
  }
}

// Counting does not change a pixel: a view within its budget renders as with no limit, and its
// work is the sum of what its samples cost.
TEST(WorkBudget, CountingLeavesTheImageUnchanged) {
  CostlyScene cs;
  cs.num_samples = 64;
  cs.weight_threshold = 1e-7f;
  const std::vector<uint8_t> bytes = BuildCostlyStream(cs);
  SceneField field;
  ASSERT_TRUE(DecodeScene(bytes.data(), bytes.size(), DecodeOptions(), &field, nullptr).ok());
  const SampleCosts costs = SceneSampleCosts(field);
  const Camera cam = FrontCamera(24);
  std::vector<float> limited(24 * 24 * 3), unlimited(24 * 24 * 3);
  RenderStats a, b;
  RenderOptions o;
  RayMarcher marcher;
  ASSERT_TRUE(marcher.Init(&field, o).ok());
  ASSERT_TRUE(marcher.RenderImage(cam, nullptr, limited.data(), &a).ok());
  o.work_budget = 0;
  ASSERT_TRUE(marcher.Init(&field, o).ok());
  ASSERT_TRUE(marcher.RenderImage(cam, nullptr, unlimited.data(), &b).ok());
  EXPECT_EQ(limited, unlimited);
  EXPECT_EQ(a.work, b.work);
  EXPECT_GT(a.samples, 0u);
  EXPECT_GT(a.color_samples, 0u);
  const uint64_t evaluated = a.samples * costs.density + a.color_samples * costs.color;
  EXPECT_GE(a.work, evaluated + a.samples * costs.position);
  EXPECT_LE(a.work, evaluated + a.rays * 64 * costs.position);
}

// A positional-encoding argument beyond the vectorised sin/cos range (|x| > 8192) takes the
// library's sin and cos, ~6x what the sample's cost counts for it: each such pair is charged
// kWideSinCosWork more. Huge basis weights made a 1.9 KB stream cost 687 s of CPU at 400x400
// within its budget (issue #60).
TEST(WorkBudget, SinesBeyondTheFastRangeAreChargedWhatTheyCost) {
  CostlyScene cs;
  cs.num_samples = 64;
  cs.weight_threshold = 1e-7f;
  cs.pe_freqs = 2;
  const std::vector<uint8_t> bytes = BuildCostlyStream(cs);
  SceneField field;
  ASSERT_TRUE(DecodeScene(bytes.data(), bytes.size(), DecodeOptions(), &field, nullptr).ok());
  // Appearance values of 1: every product is 1, so a feature is the sum of its basis row.
  ASSERT_EQ(field.appearance.storage, GridStorage::kFloat32);
  for (int m = 0; m < 3; ++m) {
    for (size_t i = 0; i < field.appearance.plane_count(m); ++i)
      field.appearance.plane_f32[m][i] = 1.f;
    for (size_t i = 0; i < field.appearance.line_count(m); ++i)
      field.appearance.line_f32[m][i] = 1.f;
  }
  field.grids_known_finite = false;
  const MlpConfig& cfg = field.mlp.config();
  std::vector<float> params(field.mlp.num_params());
  ASSERT_TRUE(field.mlp.GetParams(params.data(), params.size()).ok());
  const Camera cam = FrontCamera(16);
  auto render = [&](float basis, RenderStats* stats) {
    for (int i = 0; i < cfg.feature_dim * cfg.num_products; ++i) params[i] = basis;
    EXPECT_TRUE(field.mlp.SetParams(params.data(), params.size()).ok());
    RayMarcher marcher;
    RenderOptions o;
    o.work_budget = 0;
    EXPECT_TRUE(marcher.Init(&field, o).ok());
    std::vector<uint8_t> rgba(16 * 16 * 4);
    EXPECT_TRUE(marcher.RenderImage(cam, rgba.data(), nullptr, stats).ok());
  };
  RenderStats small, huge;
  render(1e-3f, &small);  // features 3e-3 x P: every argument in the fast range
  render(1e5f, &huge);    // features 3e5 x P: every feature argument beyond it
  ASSERT_GT(small.color_samples, 0u);
  ASSERT_EQ(small.samples, huge.samples);
  ASSERT_EQ(small.color_samples, huge.color_samples);
  // Exactly the feature arguments (F x Ff a sample) were charged more; view directions stay small.
  const uint64_t wide = huge.color_samples * cfg.feature_dim * cfg.feature_pe_freqs;
  EXPECT_EQ(huge.work - small.work, wide * kWideSinCosWork);
}

// A view rendered in bands of rays (the CLI renders 65,536 at a time) spends one budget between
// BeginView and EndView: the same rays twice within one view cost twice, and the second band is
// refused where, each with a budget of its own, both pass.
TEST(WorkBudget, BandsOfOneViewShareItsBudget) {
  CostlyScene cs;
  cs.num_samples = 256;
  cs.weight_threshold = 1e-7f;
  const std::vector<uint8_t> bytes = BuildCostlyStream(cs);
  SceneField field;
  ASSERT_TRUE(DecodeScene(bytes.data(), bytes.size(), DecodeOptions(), &field, nullptr).ok());
  const size_t n = 64;  // rays straight through the box
  std::vector<float> o(n * 3), d(n * 3), rgb(n * 3);
  for (size_t i = 0; i < n; ++i) {
    o[i * 3 + 0] = -0.5f + static_cast<float>(i) / n;
    o[i * 3 + 1] = 0.1f;
    o[i * 3 + 2] = 3.f;
    d[i * 3 + 2] = -1.f;
  }
  RenderOptions opts;
  opts.num_threads = 1;
  opts.work_budget = 0;
  RayMarcher marcher;
  ASSERT_TRUE(marcher.Init(&field, opts).ok());
  RenderStats one;
  ASSERT_TRUE(marcher.RenderRays(n, o.data(), d.data(), rgb.data(), nullptr, &one).ok());
  ASSERT_GT(one.work, uint64_t{1} << 23);  // well above a thread's share of the pool
  // A per-pixel budget that covers one band of n rays but not two.
  opts.work_budget = one.work * 3 / 2 / n;
  ASSERT_TRUE(marcher.Init(&field, opts).ok());
  for (int band = 0; band < 2; ++band) {
    EXPECT_TRUE(marcher.RenderRays(n, o.data(), d.data(), rgb.data(), nullptr).ok()) << band;
  }
  marcher.BeginView(2 * n);  // the two bands as one view of 2n pixels: the same budget in all
  ASSERT_TRUE(marcher.RenderRays(n, o.data(), d.data(), rgb.data(), nullptr).ok());
  RenderStats second;
  const Status s = marcher.RenderRays(n, o.data(), d.data(), rgb.data(), nullptr, &second);
  EXPECT_TRUE(s.ok()) << "2n pixels cover two bands: " << s.message();
  marcher.BeginView(n);  // one band's pixels for two bands: the second is refused
  ASSERT_TRUE(marcher.RenderRays(n, o.data(), d.data(), rgb.data(), nullptr).ok());
  const Status refused = marcher.RenderRays(n, o.data(), d.data(), rgb.data(), nullptr);
  EXPECT_EQ(refused.code(), kErrLimit);
  EXPECT_TRUE(Contains(refused.message(), (" x " + std::to_string(n) + " pixels").c_str()))
      << refused.message();
  marcher.EndView();
  EXPECT_TRUE(marcher.RenderRays(n, o.data(), d.data(), rgb.data(), nullptr).ok());
}

Status DecodeWith(const std::vector<uint8_t>& bytes, uint64_t work_per_byte, SceneField* field,
                  SceneInfo* info = nullptr) {
  DecodeOptions o;
  o.work_per_byte = work_per_byte;
  return DecodeScene(bytes.data(), bytes.size(), o, field, info);
}

// An OCCU chunk that flags every row and sets no voxel (SPEC 6.3 allows it): each voxel is a
// symbol that costs next to nothing. At 512^3, 3 KB asked for 2^27 symbols (~1.5 s; 1024^3 in
// 18 KB, ~11 s).
TEST(DecodeBudget, AnOccupancyMaskOfEmptyFlaggedRowsIsRefusedAsItDecodes) {
  CostlyScene cs = costly::EmptyFlaggedRows(512);
  const std::vector<uint8_t> bomb = BuildCostlyStream(cs);
  ASSERT_FALSE(bomb.empty());
  EXPECT_LT(bomb.size(), 8u * 1024u);
  SceneField field;
  const Status s = DecodeWith(bomb, kDefaultDecodeWorkPerByte, &field);
  EXPECT_EQ(s.code(), kErrLimit);
  EXPECT_TRUE(Contains(s.message(), "OCCU: decode budget spent at row") &&
              Contains(s.message(), "per byte of its") && Contains(s.message(), "--decode-budget"))
      << s.message();
  EXPECT_FALSE(field.has_mask);

  // At 256^3 (16.8 M symbols) it fits the default's base of 2^24 and what its bytes add; a
  // budget of 1 per byte refuses it, no limit accepts it.
  cs.occupancy_res = 256;
  const std::vector<uint8_t> smaller = BuildCostlyStream(cs);
  EXPECT_EQ(DecodeWith(smaller, 1, &field).code(), kErrLimit);
  for (uint64_t per_byte : {kDefaultDecodeWorkPerByte, uint64_t{0}}) {
    SceneInfo info;
    const Status ok = DecodeWith(smaller, per_byte, &field, &info);
    ASSERT_TRUE(ok.ok()) << ok.message();
    EXPECT_TRUE(field.has_mask);
    EXPECT_EQ(info.occupied_voxels, 0u);
    EXPECT_GT(info.decode_work, uint64_t{256} * 256 * 256);
  }
}

// Coefficient blocks coded to their last position: 16^3 blocks of 4095 zeros and one 1 cost
// ~15 bits each but their symbols and inverse DCT ~16,000 units; ~12 KB of them ~100 M units.
TEST(DecodeBudget, BlocksCodedToTheirFullLengthAreRefusedAsTheyDecode) {
  CostlyScene cs = costly::FullLengthBlocks(16);
  const std::vector<uint8_t> bomb = BuildCostlyStream(cs);
  ASSERT_FALSE(bomb.empty());
  EXPECT_LT(bomb.size(), 64u * 1024u);
  SceneField field;
  const Status s = DecodeWith(bomb, kDefaultDecodeWorkPerByte, &field);
  EXPECT_EQ(s.code(), kErrLimit);
  EXPECT_TRUE(Contains(s.message(), "COEF ") && Contains(s.message(), "decode budget"))
      << s.message();
  // The same through the C API, and accepted there once the budget is lifted.
  ecrf_scene* scene = ecrf_scene_create();
  EXPECT_EQ(ecrf_scene_decode(scene, bomb.data(), bomb.size(), ECRF_STORAGE_FLOAT32),
            ECRF_ERR_LIMIT);
  ASSERT_EQ(ecrf_scene_set_decode_budget(scene, 0), 0);
  EXPECT_EQ(ecrf_scene_decode(scene, bomb.data(), bomb.size(), ECRF_STORAGE_FLOAT32), 0)
      << ecrf_scene_message(scene);
  ecrf_scene_destroy(scene);

  // The same grids with all-zero blocks cost one symbol per block: well within the budget.
  cs.blocks = 0;
  const std::vector<uint8_t> zeros = BuildCostlyStream(cs);
  SceneInfo info;
  ASSERT_TRUE(DecodeWith(zeros, kDefaultDecodeWorkPerByte, &field, &info).ok());
  EXPECT_LT(info.decode_work, uint64_t{1} << 20);
}

// Neighbour contexts over a large block grid (2048^2 planes of rank 1 in 16^3 blocks: 67 MB of
// contexts a plane chunk) are charged for allocating and clearing them: 582 bytes of stream cleared
// 400 MB at 171 decode units a byte before (issue #60); now the default budget refuses it, and
// with no limit its work counts each chunk's NB[1] * NB[2] * (V + 2) / 16.
TEST(DecodeBudget, NeighbourContextsAreChargedForTheirMemory) {
  const std::vector<uint8_t> bytes = BuildCostlyStream(costly::NeighbourContexts2048());
  ASSERT_FALSE(bytes.empty());
  EXPECT_LT(bytes.size(), 1024u);
  SceneField field;
  const Status s = DecodeWith(bytes, kDefaultDecodeWorkPerByte, &field);
  EXPECT_EQ(s.code(), kErrLimit);
  EXPECT_TRUE(Contains(s.message(), "neighbour contexts") && Contains(s.message(), "decode budget"))
      << s.message();
  SceneInfo info;
  ASSERT_TRUE(DecodeWith(bytes, 0, &field, &info).ok());
  const uint64_t plane_chunk = uint64_t{2048 / 16} * (2048 / 16) * (16 * 16 * 16 + 2) / 16;
  EXPECT_GE(info.decode_work, 6 * plane_chunk);  // two grids of three planes
  EXPECT_LT(info.decode_work, 6 * plane_chunk + (uint64_t{1} << 20));
}

// Real streams cost a small fraction of the default: the conformance vectors and a trained one.
TEST(DecodeBudget, RealStreamsCostLittleOfTheDefault) {
  const std::string dir = std::string(ECRF_SOURCE_DIR) + "/tests/conformance/";
  for (const char* name : {"scene_builtin.ecrf", "scene_wide_contexts.ecrf", "scene_16bit.ecrf",
                           "scene_quantized_mlp.ecrf", "scene_unbounded.ecrf"}) {
    std::ifstream in(dir + name, std::ios::binary);
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                     std::istreambuf_iterator<char>());
    ASSERT_FALSE(bytes.empty()) << name;
    SceneField field;
    SceneInfo info;
    const Status s = DecodeWith(bytes, kDefaultDecodeWorkPerByte, &field, &info);
    ASSERT_TRUE(s.ok()) << name << ": " << s.message();
    EXPECT_GT(info.decode_work, 0u) << name;
    // Per byte beyond the base: at most 1/8 of what the default allows.
    EXPECT_LT(info.decode_work, kDecodeWorkBase / 8 + kDefaultDecodeWorkPerByte / 8 * bytes.size())
        << name << ": " << info.decode_work << " units for " << bytes.size() << " bytes";
  }
}

}  // namespace
}  // namespace dec
}  // namespace ecrf
