// The encoder on a scene described in the stream's own terms, with nothing of the trainer: the
// decoder reads back what was described, and a description whose arrays disagree with its header
// is refused before anything is coded.
#include "encoder/scene_description.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "decoder/scene_decoder.h"
#include "encoder/scene_encoder.h"
#include "format/mlp_coder.h"
#include "tests/common/decode_or_die.h"

namespace ecrf {
namespace encoder {
namespace {

// A 6 x 5 x 4 grid, every mode of rank 2 (density) or 1 (appearance), smooth non-zero values
// (no component is all zero, so none is dropped), a head of hidden width 8 and a mask.
SceneDescription SmallScene() {
  SceneDescription s;
  SceneHeader& h = s.header;
  h.res[0] = 6;
  h.res[1] = 5;
  h.res[2] = 4;
  for (int m = 0; m < 3; ++m) {
    h.ranks[0][m] = 2;
    h.ranks[1][m] = 1;
  }
  h.feature_dim = 4;
  h.hidden = 8;
  h.step_size = 0.05f;
  h.num_samples = 64;
  for (int g = 0; g < 2; ++g) {
    for (int t = 0; t < 6; ++t) {
      int extent[3];
      SceneTensorExtent(h, g, t, extent);
      std::vector<float>& tensor = s.tensors[size_t(g)][size_t(t)];
      tensor.resize(size_t(extent[0]) * extent[1] * extent[2]);
      for (size_t i = 0; i < tensor.size(); ++i)
        tensor[i] = 0.5f + 0.01f * float(i % 17) + 0.1f * t;
    }
  }
  const MlpLayout mlp = MakeMlpLayout(h.feature_dim, h.total_rank(1), h.hidden, h.feature_pe_freqs,
                                      h.viewdir_pe_freqs);
  s.head_params.assign(MlpParamCount(mlp), 0.125f);
  OccupancyDescription& mask = s.mask.emplace();
  mask.aabb_min = {-1.f, -1.f, -1.f};
  mask.aabb_max = {1.f, 1.f, 1.f};
  mask.res = {3, 3, 2};
  mask.occupancy = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0};
  return s;
}

TEST(SceneDescription, DecodesToWhatWasDescribed) {
  const SceneDescription s = SmallScene();
  EncodeOptions o;
  o.blocks.plane_block[0] = 2;  // blocks never span more channels than a mode has
  o.blocks.plane_block[1] = 4;
  o.blocks.plane_block[2] = 4;
  o.blocks.line_block[1] = 1;
  o.blocks.line_block[2] = 4;
  EncodeReport report;
  const dec::SceneField field = DecodeOrDie(EncodeScene(s, o, &report));
  for (int a = 0; a < 3; ++a) EXPECT_EQ(field.res[a], s.header.res[a]);
  for (int m = 0; m < 3; ++m) {
    EXPECT_EQ(field.density.ranks[m], 2);
    EXPECT_EQ(field.appearance.ranks[m], 1);
    EXPECT_EQ(report.ranks_out[0][m], 2);
  }
  EXPECT_FLOAT_EQ(field.step_size, 0.05f);
  EXPECT_EQ(field.n_samples, 64);
  ASSERT_TRUE(field.has_mask);
  EXPECT_EQ(field.mask.occupied_count(), 4u);
  EXPECT_GT(report.occupancy_bytes, 0u);
}

TEST(SceneDescription, ArraysThatDisagreeWithTheHeaderAreRefused) {
  EncodeOptions o;
  o.blocks.plane_block[0] = 1;
  o.blocks.line_block[1] = 1;
  EXPECT_NO_THROW(EncodeScene(SmallScene(), o));

  SceneDescription short_tensor = SmallScene();
  short_tensor.tensors[1][4].pop_back();
  EXPECT_THROW(EncodeScene(short_tensor, o), std::invalid_argument);

  SceneDescription wider_rank = SmallScene();
  wider_rank.header.ranks[0][2] = 3;  // the tensors still hold rank 2
  EXPECT_THROW(EncodeScene(wider_rank, o), std::invalid_argument);

  SceneDescription long_head = SmallScene();
  long_head.head_params.push_back(0.f);
  EXPECT_THROW(EncodeScene(long_head, o), std::invalid_argument);

  SceneDescription short_mask = SmallScene();
  short_mask.mask->occupancy.pop_back();
  EXPECT_THROW(EncodeScene(short_mask, o), std::invalid_argument);
}

}  // namespace
}  // namespace encoder
}  // namespace ecrf
