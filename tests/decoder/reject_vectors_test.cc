// The must-reject conformance streams (tests/conformance/reject/, SPEC.md 7.7): each checked-in
// file is what conformance/reject_vectors.h builds, byte for byte, and the decoder refuses it at
// its stage with its category, through the C++ API and the C API alike.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "conformance/reject_vectors.h"
#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"
#include "ecrf/decoder.h"

namespace ecrf {
namespace dec {
namespace {

const std::string kRejectDir = std::string(ECRF_SOURCE_DIR) + "/tests/conformance/reject/";

std::vector<uint8_t> ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)),
                              std::istreambuf_iterator<char>());
}

TEST(RejectVectors, EachIsRefusedAtItsStageWithItsCategory) {
  const std::vector<conformance::RejectVector> vectors = conformance::RejectVectors();
  ASSERT_GE(vectors.size(), 16u);
  int normative = 0, render_stage = 0;
  for (const conformance::RejectVector& r : vectors) {
    SCOPED_TRACE(r.name);
    const std::vector<uint8_t> stored = ReadFile(kRejectDir + r.name + ".ecrf");
    EXPECT_EQ(stored, r.bytes) << "rebuild with `ecrf conformance --write tests/conformance`";
    const bool at_render = std::string(r.stage) == "render";
    SceneField field;
    Status s = DecodeScene(r.bytes.data(), r.bytes.size(), DecodeOptions(), &field, nullptr);
    ASSERT_EQ(s.ok(), at_render) << s.message();
    if (at_render) {
      RayMarcher marcher;
      s = marcher.Init(&field, RenderOptions());
    }
    EXPECT_EQ(s.code(), r.code) << s.message();

    ecrf_scene* scene = ecrf_scene_create();
    const int rc = ecrf_scene_decode(scene, r.bytes.data(), r.bytes.size(), ECRF_STORAGE_FLOAT32);
    if (at_render) {
      ASSERT_EQ(rc, 0) << ecrf_scene_message(scene);
      ecrf_render_options o;
      ecrf_render_options_default(&o);
      EXPECT_EQ(ecrf_scene_check_render(scene, &o), r.code) << ecrf_scene_message(scene);
    } else {
      EXPECT_EQ(rc, r.code) << ecrf_scene_message(scene);
    }
    ecrf_scene_destroy(scene);
    normative += !r.budget;
    render_stage += at_render;
  }
  EXPECT_GE(normative, 12);
  EXPECT_EQ(render_stage, 1);
  // expected.txt lists them all, as the portable checker reads them.
  const std::vector<uint8_t> text = ReadFile(kRejectDir + "expected.txt");
  EXPECT_EQ(std::string(text.begin(), text.end()), conformance::RejectExpectedText(vectors));
}

// A budget vector is refused by the default budgets only: lifted, it decodes (a decoder with
// other budgets decodes it exactly).
TEST(RejectVectors, BudgetVectorsDecodeWhenTheBudgetIsLifted) {
  for (const conformance::RejectVector& r : conformance::RejectVectors()) {
    if (!r.budget || r.name != "reject_budget_full_length_blocks") continue;
    SceneField field;
    DecodeOptions o;
    o.work_per_byte = 0;
    const Status s = DecodeScene(r.bytes.data(), r.bytes.size(), o, &field, nullptr);
    EXPECT_TRUE(s.ok()) << s.message();
    return;
  }
  FAIL() << "reject_budget_full_length_blocks is missing";
}

}  // namespace
}  // namespace dec
}  // namespace ecrf
