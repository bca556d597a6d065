// tests/conformance/manifest.json (SPEC.md 6.5, 7.1, 7.7): every scene vector decodes to the
// manifest's three checksums, and the renderer with its default accelerations reproduces each
// reference render, from the manifest's exact camera, within the pixel tolerance of 7.7.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "conformance/conformance_camera.h"
#include "conformance/scene_vectors.h"
#include "tools/conformance_manifest.h"
#include "tools/decoded_scene.h"
#include "trainer/data/file_io.h"
#include "trainer/data/image_io.h"
#include "trainer/train/checkpoint.h"

namespace ecrf {
namespace tools {
namespace {

const std::string kDir = std::string(ECRF_SOURCE_DIR) + "/tests/conformance/";

nlohmann::json Manifest() {
  const std::vector<uint8_t> text = trainer::ReadWholeFile(kDir + "manifest.json");
  return nlohmann::json::parse(text.begin(), text.end());
}

TEST(ConformanceManifest, HexFloatsRoundTripExactlyAndInexactValuesAreRefused) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<uint32_t> bits;
  int checked = 0;
  while (checked < 2000) {
    const uint32_t u = bits(rng);
    float f;
    std::memcpy(&f, &u, 4);
    if (!std::isfinite(f)) continue;
    const float back = ParseExactFloat(HexFloat(f), "test");
    EXPECT_EQ(std::memcmp(&back, &f, 4), 0) << HexFloat(f);
    ++checked;
  }
  EXPECT_EQ(ParseExactFloat("0x1.8p+5", "x"), 48.f);
  EXPECT_EQ(ParseExactFloat("0.5", "x"), 0.5f);
  for (const char* bad : {"0.1", "1e39", "nan", "inf", "", "0x1p+0 ", "12abc", "0x1.000001p+0"}) {
    EXPECT_THROW(ParseExactFloat(bad, "camera.fx"), std::runtime_error) << bad;
  }
}

TEST(ConformanceManifest, ListsEveryVectorWithItsParameters) {
  const nlohmann::json m = Manifest();
  ASSERT_EQ(m.at("scene_vectors").size(), conformance::SceneVectors().size() + 1);
  for (const auto& v : conformance::SceneVectors()) {
    const nlohmann::json* e = nullptr;
    for (const auto& s : m["scene_vectors"]) {
      if (s["file"] == std::string(v.name) + ".ecrf") e = &s;
    }
    ASSERT_NE(e, nullptr) << v.name;
    for (int a = 0; a < 3; ++a) EXPECT_EQ((*e)["grid"][a], v.res[a]) << v.name;
    EXPECT_EQ((*e)["coef_bits"], v.coef_bits) << v.name;
    EXPECT_EQ((*e)["occupancy"].is_null(), v.occupancy == conformance::OccupancyKind::kNone)
        << v.name;
    const dec::Camera cam = CameraFromJson((*e)["render"]["camera"], v.name);
    EXPECT_EQ(cam.width, 48);
    EXPECT_EQ(cam.height, 48);
  }
  // Five narrow-context, four wide-context and four neighbour-context vectors; a neighbour
  // vector's block grid holds its blocks.
  EXPECT_EQ(m.at("coefficient_vectors").size(), 13u);
  int wide = 0, neighbour = 0;
  for (const auto& c : m.at("coefficient_vectors")) {
    wide += c.at("contexts") == 1;
    neighbour += c.at("contexts") == 2;
    EXPECT_EQ(c.at("grid")[0].get<int>() * c.at("grid")[1].get<int>() * c.at("grid")[2].get<int>(),
              c.at("contexts") == 2 ? c.at("blocks").get<int>() : 1);
  }
  EXPECT_EQ(wide, 4);
  EXPECT_EQ(neighbour, 4);
}

TEST(ConformanceManifest, ScenesMatchEveryChecksumAndRenderWithinTolerance) {
  int checked = 0;
  const nlohmann::json manifest = Manifest();
  for (const nlohmann::json& e : manifest.at("scene_vectors")) {
    const std::string file = e.at("file");
    const LoadedScene s = LoadSceneFile(kDir + file);
    const SceneChecksums sums = ComputeSceneChecksums(*s.field);
    EXPECT_EQ(sums.grids, e["md5"]["grids"]) << file;
    EXPECT_EQ(sums.occupancy, e["md5"]["occupancy"]) << file;
    EXPECT_EQ(sums.mlp, e["md5"]["mlp"]) << file;
    if (!s.field->has_mask) EXPECT_EQ(sums.occupancy, "d41d8cd98f00b204e9800998ecf8427e") << file;

    const dec::Camera cam = CameraFromJson(e["render"]["camera"], file);
    dec::RenderOptions options;  // default accelerations, early termination included (SPEC.md 7.8)
    options.num_threads = 2;
    dec::RayMarcher marcher;
    ASSERT_TRUE(marcher.Init(s.field.get(), options).ok());
    std::vector<uint8_t> rgba(size_t(cam.width) * cam.height * 4);
    ASSERT_TRUE(marcher.RenderImage(cam, rgba.data(), nullptr).ok());
    const trainer::Image ref = trainer::LoadImage(kDir + e["render"]["png"].get<std::string>());
    std::vector<uint8_t> ref8(ref.pixels.size());
    for (size_t i = 0; i < ref8.size(); ++i) ref8[i] = uint8_t(std::lround(ref.pixels[i] * 255.f));
    const RenderAgreement a = CompareRenders(rgba, ref8);
    EXPECT_TRUE(a.Conforms()) << file << ": " << a.within_two_codes << "/" << a.pixels;
    EXPECT_GE(a.psnr_db, 40.0) << file;
    ++checked;
  }
  // Eighteen hand-made scenes (two unbounded, two forward-facing, two 1.4 streams, one 1.5
  // stream, a 1.6 stream with the deferred head, two 1.7 streams with spherical-harmonics colour,
  // a 1.8 stream with one hidden layer, a 1.9 stream with ReLU density, quantized MLPs) and the
  // trained one.
  EXPECT_EQ(checked, 19);
  // And the must-reject streams (SPEC.md 7.7): 27, each with its stage, code and reason.
  EXPECT_EQ(manifest.at("reject_vectors").size(), 27u);
  for (const nlohmann::json& r : manifest.at("reject_vectors")) {
    EXPECT_TRUE(r.at("stage") == "decode" || r.at("stage") == "render") << r.dump();
    EXPECT_LT(r.at("code").get<int>(), 0) << r.dump();
    EXPECT_FALSE(r.at("why").get<std::string>().empty()) << r.dump();
  }
}

TEST(ConformanceManifest, RenderAgreementCountsPixelsByTheirWorstChannel) {
  std::vector<uint8_t> rgba(100 * 4, 100), ref(100 * 3, 100);
  EXPECT_TRUE(CompareRenders(rgba, ref).Conforms());
  EXPECT_EQ(CompareRenders(rgba, ref).max_difference, 0);
  ref[5 * 3 + 2] = 103;  // one pixel, one channel, 3 codes off: 99 of 100 within 2 codes
  RenderAgreement a = CompareRenders(rgba, ref);
  EXPECT_EQ(a.within_two_codes, 99u);
  EXPECT_EQ(a.max_difference, 3);
  EXPECT_TRUE(a.Conforms());
  ref[7 * 3 + 0] = 0;  // a second pixel 100 codes off in one channel: 98%
  a = CompareRenders(rgba, ref);
  EXPECT_FALSE(a.Conforms());
  // MSE = (3^2 + 100^2) / 255^2 / 300 values.
  EXPECT_NEAR(a.psnr_db, -10.0 * std::log10((9.0 + 10000.0) / (255.0 * 255.0) / 300.0), 1e-9);
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
