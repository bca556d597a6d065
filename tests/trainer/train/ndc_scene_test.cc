// The forward-facing scene model end to end: the NDC ray (SPEC.md 7.2.2) against the projective
// map it stands for, the fitted reference camera and NDC box, the 1.3 stream with its NDCP chunk
// and its refusals, and the trainer's renderer against the decoder's on one NDC field.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "decoder/ndc.h"
#include "decoder/ray_marcher.h"
#include "decoder/scene_decoder.h"
#include "encoder/scene_encoder.h"
#include "format/byte_io.h"
#include "format/container.h"
#include "format/ndc_frame.h"
#include "format/scene_header.h"
#include "tests/common/decode_or_die.h"
#include "tests/common/renderer_agreement.h"
#include "trainer/data/camera.h"
#include "trainer/data/scene_fit.h"
#include "trainer/model/volume_render.h"
#include "trainer/rate/coded_model.h"

namespace ecrf {
namespace trainer {
namespace {

// The NDC of a point in reference coordinates (z < 0): TensoRF's projection, in double.
void ProjectToNdc(const NdcFrame& f, const double p[3], double out[3]) {
  out[0] = -f.scale[0] * p[0] / p[2];
  out[1] = -f.scale[1] * p[1] / p[2];
  out[2] = 1.0 + 2.0 * f.near_plane / p[2];
}

// A frame that is not the identity: rotated 30 degrees about x, shifted, scaled by 2.
NdcFrame TiltedFrame() {
  NdcFrame f;
  const double c = std::cos(0.5236), s = std::sin(0.5236);
  const double rows[3][4] = {{2, 0, 0, 0.3}, {0, 2 * c, -2 * s, -0.2}, {0, 2 * s, 2 * c, 1.5}};
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 4; ++k) f.world_to_ref[4 * r + k] = float(rows[r][k]);
  }
  f.scale[0] = 1.7f;
  f.scale[1] = 2.2f;
  f.near_plane = 0.8f;
  return f;
}

void ToReference(const NdcFrame& f, const double p[3], double out[3]) {
  for (int a = 0; a < 3; ++a) {
    out[a] = f.world_to_ref[4 * a + 3];
    for (int k = 0; k < 3; ++k) out[a] += double(f.world_to_ref[4 * a + k]) * p[k];
  }
}

TEST(NdcRay, IsTheStraightImageOfTheWorldRayBeyondTheNearPlane) {
  const NdcFrame f = TiltedFrame();
  int checked = 0;
  for (int r = 0; r < 50; ++r) {
    const float o[3] = {0.1f * (r % 7) - 0.3f, 0.05f * (r % 5), 0.02f * r - 0.5f};
    float d[3] = {0.3f * std::sin(0.7f * r), 0.2f * std::cos(1.3f * r) - 0.5f, -1.f};
    const float len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (float& v : d) v /= len;
    float ndc_o[3], ndc_d[3];
    ASSERT_TRUE(NdcRay(f, o, d, ndc_o, ndc_d)) << r;
    EXPECT_NEAR(ndc_o[2], -1.f, 1e-5f);  // the ray starts on the near plane
    EXPECT_NEAR(ndc_d[0] * ndc_d[0] + ndc_d[1] * ndc_d[1] + ndc_d[2] * ndc_d[2], 1.f, 1e-5f);
    EXPECT_GT(ndc_d[2], 0.f);  // towards infinity (NDC z = 1)
    // World points beyond the near plane project onto the NDC line, in order.
    double previous = -2;
    for (double t = 0.5; t < 200; t *= 1.7) {
      const double p[3] = {o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t};
      double ref[3], q[3];
      ToReference(f, p, ref);
      if (!(ref[2] < -f.near_plane)) continue;
      ProjectToNdc(f, ref, q);
      const double s = (q[2] - ndc_o[2]) / ndc_d[2];
      EXPECT_GT(s, previous);
      previous = s;
      for (int a = 0; a < 2; ++a)
        EXPECT_NEAR(q[a], ndc_o[a] + ndc_d[a] * s, 2e-5 * (1 + std::fabs(q[a]))) << r;
      ++checked;
    }
  }
  EXPECT_GT(checked, 300);
}

TEST(NdcRay, RefusesRaysThatNeverReachTheFarSide) {
  NdcFrame f;  // identity: the reference camera looks down -z
  const float o[3] = {0.f, 0.f, 0.f};
  float ndc_o[3], ndc_d[3];
  for (const float dz : {0.f, 0.3f, 1.f}) {
    const float d[3] = {std::sqrt(1.f - dz * dz), 0.f, dz};
    EXPECT_FALSE(NdcRay(f, o, d, ndc_o, ndc_d)) << dz;
  }
  const float nan_dir[3] = {0.f, 0.f, std::nanf("")};
  EXPECT_FALSE(NdcRay(f, o, nan_dir, ndc_o, ndc_d));
  const float straight[3] = {0.f, 0.f, -1.f};
  ASSERT_TRUE(NdcRay(f, o, straight, ndc_o, ndc_d));
  EXPECT_EQ(ndc_o[0], 0.f);
  EXPECT_EQ(ndc_o[2], -1.f);
  EXPECT_EQ(ndc_d[2], 1.f);
}

std::vector<Camera> ForwardCameras() {
  // A 3 x 3 patch of cameras looking along +y (world z up), slightly toed in.
  std::vector<Camera> cameras;
  for (int k = 0; k < 9; ++k) {
    Camera c;
    c.width = 40;
    c.height = 30;
    c.fx = c.fy = 35;
    c.cx = 21;
    c.cy = 14;
    const double x = 0.2 * (k % 3 - 1), z = 1.0 + 0.1 * (k / 3 - 1), yaw = -0.05 * (k % 3 - 1);
    // Columns right, up, back, centre; looking down -back = (sin yaw, cos yaw, 0).
    const double right[3] = {std::cos(yaw), -std::sin(yaw), 0}, up[3] = {0, 0, 1};
    const double back[3] = {-std::sin(yaw), -std::cos(yaw), 0}, centre[3] = {x, -3, z};
    for (int a = 0; a < 3; ++a) {
      c.c2w[a][0] = right[a];
      c.c2w[a][1] = up[a];
      c.c2w[a][2] = back[a];
      c.c2w[a][3] = centre[a];
    }
    cameras.push_back(c);
  }
  return cameras;
}

TEST(NdcFit, ReferenceCameraIsTheAveragePoseAndTheBoxHoldsEveryPixelRay) {
  const std::vector<Camera> cameras = ForwardCameras();
  EXPECT_TRUE(CamerasFaceOneWay(cameras));
  const NdcFrame f = FitNdcFrame(cameras, 1.2);
  EXPECT_FLOAT_EQ(f.near_plane, float(1.2 * kNdcNearShare));
  EXPECT_FLOAT_EQ(f.scale[0], 2 * 35.f / 40);
  EXPECT_FLOAT_EQ(f.scale[1], 2 * 35.f / 30);
  // The average camera sits at (0, -3, 1) looking along +y: the world origin is 3 units ahead.
  const double origin[3] = {0, 0, 1}, centre[3] = {0, -3, 1};
  double ref[3];
  ToReference(f, origin, ref);
  EXPECT_NEAR(ref[0], 0, 1e-5);
  EXPECT_NEAR(ref[1], 0, 1e-5);
  EXPECT_NEAR(ref[2], -3, 1e-5);
  ToReference(f, centre, ref);
  for (double v : ref) EXPECT_NEAR(v, 0, 1e-5);

  const Aabb box = FitNdcBox(cameras, f);
  EXPECT_EQ(box.min[2], -1.f);
  EXPECT_EQ(box.max[2], 1.f);
  for (const Camera& c : cameras) {
    for (int j = 0; j < c.height; j += 3) {
      for (int i = 0; i < c.width; i += 3) {
        float o[3], d[3], ndc_o[3], ndc_d[3];
        GenerateRay(c, i, j, o, d);
        ASSERT_TRUE(NdcRay(f, o, d, ndc_o, ndc_d));
        const float t_far = (1.f - ndc_o[2]) / ndc_d[2];
        for (const float t : {0.f, t_far}) {
          for (int a = 0; a < 2; ++a) {
            const float v = ndc_o[a] + ndc_d[a] * t;
            EXPECT_GE(v, box.min[a]);
            EXPECT_LE(v, box.max[a]);
          }
        }
      }
    }
  }
  // Not much more than the views: the central camera's image spans about [-1, 1] in x and y.
  EXPECT_LT(box.max[0] - box.min[0], 3.f);
  EXPECT_LT(box.max[1] - box.min[1], 3.f);
}

TensorfModel SmallForwardModel(uint64_t seed,
                               DensityActivation activation = DensityActivation::kSoftplus) {
  TensorfConfig c;
  c.density_activation = activation;
  c.density_ranks = {2, 3, 2};
  c.app_ranks = {3, 2, 3};
  c.head.num_products = 8;
  c.head.feature_dim = 6;
  c.head.hidden = 16;
  c.scene_model = SceneModel::kForward;
  c.ndc = TiltedFrame();
  c.aabb.min = {-1.4f, -1.3f, -1.f};
  c.aabb.max = {1.5f, 1.2f, 1.f};
  c.near = 0.f;
  c.far = 10.f;
  c.white_background = false;
  c.density_shift = activation == DensityActivation::kRelu ? -0.05f : -3.f;
  TensorfModel model(c);
  model.Initialize({17, 15, 16}, seed);
  return model;
}

std::vector<uint8_t> EncodeForward(const TensorfModel& model,
                                   int max_version_minor = kVersionMinor) {
  encoder::EncodeOptions o;
  o.max_version_minor = max_version_minor;
  o.mlp_float32 = true;
  o.mlp_max_level = 0;
  o.drop_zero_components = false;
  return EncodeScene(model, o);
}

// Rays from around the reference camera, most of them through the NDC box.
void ForwardRays(std::vector<float>* origins, std::vector<float>* dirs) {
  const NdcFrame f = TiltedFrame();
  for (int r = 0; r < 200; ++r) {
    // In reference coordinates: centres near 0, directions within 40 degrees of -z.
    const double ref_o[3] = {0.05 * (r % 5 - 2), 0.04 * (r % 3 - 1), 0.1 * (r % 4)};
    const double ref_d[3] = {0.6 * std::sin(0.37 * r), 0.5 * std::cos(0.53 * r), -1.0};
    // World = A^-1 (ref - b); A is 2 R with R a rotation, so A^-1 = R^T / 2.
    double o[3] = {0, 0, 0}, d[3] = {0, 0, 0};
    for (int a = 0; a < 3; ++a) {
      for (int k = 0; k < 3; ++k) {
        const double rt = double(f.world_to_ref[4 * k + a]) / 4.0;  // (2R)^T / 4 = R^T / 2
        o[a] += rt * (ref_o[k] - f.world_to_ref[4 * k + 3]);
        d[a] += rt * ref_d[k];
      }
    }
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int a = 0; a < 3; ++a) {
      origins->push_back(float(o[a]));
      dirs->push_back(float(d[a] / len));
    }
  }
}

// The trainer's renderer on `model` holding the decoded grids of `field` (its float grids would
// differ by the quantization) against the decoder's, on rays through the NDC box.
void ExpectBothRenderersAgree(const dec::SceneField& field, TensorfModel model,
                              const std::vector<float>& origins, const std::vector<float>& dirs) {
  model.UpdateAlphaMask({9, 8, 9});
  LoadDecodedGrids(field, &model);
  const RendererAgreement r = RenderBothWays(model, field, origins, dirs);
  EXPECT_LT(r.worst, 2e-3f);
  EXPECT_GT(r.spread, 0.01f);
  EXPECT_GT(r.decoder_samples, origins.size() / 3 * 5);
}

TEST(ForwardScene, StreamIsVersion13WithAnNdcpChunkAndTheDecoderRendersWhatTheTrainerRenders) {
  TensorfModel model = SmallForwardModel(5);
  model.UpdateAlphaMask({9, 8, 9});
  const std::vector<uint8_t> bytes = EncodeForward(model, 3);
  EXPECT_EQ(bytes[5], 3);  // version_minor: the forward-facing model is a 1.3 feature
  // HEAD (12 + 90 bytes after the 8-byte file header), then NDCP.
  EXPECT_EQ(std::string(bytes.begin() + 8 + 12 + kSceneHeaderBytes,
                        bytes.begin() + 8 + 12 + kSceneHeaderBytes + 4),
            "NDCP");
  const dec::SceneField field = DecodeOrDie(bytes);
  ASSERT_EQ(field.scene_model, SceneModel::kForward);
  for (int k = 0; k < 12; ++k)
    EXPECT_EQ(field.ndc.world_to_ref[k], model.config().ndc.world_to_ref[k]);
  EXPECT_EQ(field.ndc.scale[0], model.config().ndc.scale[0]);
  EXPECT_EQ(field.ndc.scale[1], model.config().ndc.scale[1]);
  EXPECT_EQ(field.ndc.near_plane, model.config().ndc.near_plane);
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(field.aabb_min[a], model.aabb().min[a]);
    EXPECT_EQ(field.aabb_max[a], model.aabb().max[a]);
  }

  std::vector<float> origins, dirs;
  ForwardRays(&origins, &dirs);
  ExpectBothRenderersAgree(field, SmallForwardModel(5), origins, dirs);

  // A ray looking away from the reference camera's view sees only the background.
  const float back_o[3] = {0.f, 0.f, 0.f};
  float back_d[3];
  for (int a = 0; a < 3; ++a) back_d[a] = -dirs[a];
  float rgb[3], alpha = 1.f;
  dec::RayMarcher marcher;
  ASSERT_TRUE(marcher.Init(&field, dec::RenderOptions()).ok());
  ASSERT_TRUE(marcher.RenderRays(1, back_o, back_d, rgb, &alpha, nullptr).ok());
  EXPECT_EQ(alpha, 0.f);
  for (float v : rgb) EXPECT_EQ(v, 0.f);
}

// ReLU density is a 1.9 feature: HEAD grows by its density_activation byte, and the decoder's
// sigma is the trainer's.
TEST(ForwardScene, ReluDensityIsVersion19AndTheDecoderRendersWhatTheTrainerRenders) {
  TensorfModel model = SmallForwardModel(6, DensityActivation::kRelu);
  model.UpdateAlphaMask({9, 8, 9});
  const std::vector<uint8_t> bytes = EncodeForward(model);
  EXPECT_EQ(bytes[5], kDensityActivationMinVersionMinor);
  EXPECT_EQ(std::string(bytes.begin() + 8 + 12 + kSceneHeaderBytes + 1,
                        bytes.begin() + 8 + 12 + kSceneHeaderBytes + 5),
            "NDCP");
  EXPECT_THROW(EncodeForward(model, 8), std::invalid_argument);  // 1.8 cannot say it
  const dec::SceneField field = DecodeOrDie(bytes);
  EXPECT_EQ(field.density_activation, DensityActivation::kRelu);
  EXPECT_EQ(field.density_shift, -0.05f);
  std::vector<float> origins, dirs;
  ForwardRays(&origins, &dirs);
  ExpectBothRenderersAgree(field, SmallForwardModel(6, DensityActivation::kRelu), origins, dirs);
}

// The stream re-framed with the payload of chunk `name` dropped (empty patch) or with `patch`
// written at `offset` into it (valid CRCs throughout: only the decoder's checks can refuse it).
std::vector<uint8_t> Rewrite(const std::vector<uint8_t>& bytes, const char* name, size_t offset,
                             const std::vector<uint8_t>& patch) {
  ContainerReader reader;
  EXPECT_TRUE(reader.Open(bytes.data(), bytes.size()).ok());
  ContainerWriter writer(bytes[5]);
  for (;;) {
    ChunkView chunk;
    bool done = false;
    EXPECT_TRUE(reader.Next(&chunk, &done).ok());
    if (done) break;
    char type[5];
    ChunkTypeName(chunk.type, type);
    std::vector<uint8_t> payload(chunk.data, chunk.data + chunk.size);
    if (std::string(type) == name) {
      if (patch.empty()) continue;
      std::copy(patch.begin(), patch.end(), payload.begin() + offset);
    }
    writer.AddChunk(chunk.type, payload);
  }
  return writer.Finish();
}

std::vector<uint8_t> F32Bytes(float v) {
  ByteWriter w;
  w.F32(v);
  return w.bytes();
}

Status Decode(const std::vector<uint8_t>& bytes) {
  dec::SceneField field;
  return dec::DecodeScene(bytes.data(), bytes.size(), dec::DecodeOptions(), &field, nullptr);
}

TEST(ForwardScene, DecoderRefusesAMissingOrBadNdcpChunk) {
  const std::vector<uint8_t> bytes = EncodeForward(SmallForwardModel(7));
  ASSERT_TRUE(Decode(bytes).ok());
  EXPECT_EQ(Decode(Rewrite(bytes, "NDCP", 0, {})).code(), kErrCorrupt);  // OCCU where NDCP belongs
  EXPECT_EQ(Decode(Rewrite(bytes, "NDCP", 48, F32Bytes(-1.f))).code(), kErrCorrupt);  // scale_x
  EXPECT_EQ(Decode(Rewrite(bytes, "NDCP", 56, F32Bytes(0.f))).code(), kErrCorrupt);   // near plane
  EXPECT_EQ(Decode(Rewrite(bytes, "NDCP", 4, F32Bytes(std::nanf("")))).code(), kErrCorrupt);
  EXPECT_TRUE(Decode(Rewrite(bytes, "NDCP", 56, F32Bytes(2.f))).ok());
  // HEAD saying "object" before an NDCP chunk: the chunk is out of order.
  EXPECT_EQ(Decode(Rewrite(bytes, "HEAD", 89, {0})).code(), kErrCorrupt);
}

TEST(ForwardScene, TrainStepLowersTheLossThroughNdc) {
  TensorfModel model = SmallForwardModel(6);
  std::vector<float> origins, dirs, target;
  ForwardRays(&origins, &dirs);
  const int n = int(origins.size() / 3);
  for (int r = 0; r < n; ++r) {
    target.push_back(0.8f);
    target.push_back(0.3f * (1 + std::cos(0.37f * r)));
    target.push_back(0.1f);
  }
  double first = 0, last = 0;
  for (int it = 0; it < 60; ++it) {
    model.ZeroGrads();
    const TrainStepStats s = TrainStep(model, n, origins.data(), dirs.data(), target.data(), it);
    if (it == 0) first = s.loss;
    last = s.loss;
    for (auto& a : model.NamedParameters()) {
      for (size_t i = 0; i < a.size; ++i) a.data[i] -= 0.5f * a.grad[i];
    }
  }
  EXPECT_LT(last, 0.5 * first);
}

}  // namespace
}  // namespace trainer
}  // namespace ecrf
