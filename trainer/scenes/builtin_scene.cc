#include "trainer/scenes/builtin_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "trainer/scenes/procedural_math.h"
#include "trainer/scenes/still_life.h"

namespace ecrf::trainer {
namespace {

using procedural::Cross;
using procedural::kPi;
using procedural::Normalized;
using procedural::Random;
using procedural::Vec3;

Vec3 Shade(Vec3 origin, Vec3 dir) {
  Vec3 colour;
  return procedural::ShadeStillLife(origin, dir, &colour) ? colour : Vec3{1, 1, 1};
}

Camera LookAtOrigin(Vec3 position, int width, int height) {
  Camera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = FocalFromFieldOfView(width, kBuiltinFieldOfView);
  camera.fy = camera.fx;
  camera.cx = 0.5 * width;
  camera.cy = 0.5 * height;
  const Vec3 forward = Normalized(Vec3{} - position);
  const Vec3 right = Normalized(Cross(forward, {0, 0, 1}));
  const Vec3 up = Cross(right, forward);
  const Vec3 columns[4] = {right, up, forward * -1.0, position};  // OpenGL: looks down -z
  for (int c = 0; c < 4; ++c) {
    camera.c2w[0][c] = columns[c].x;
    camera.c2w[1][c] = columns[c].y;
    camera.c2w[2][c] = columns[c].z;
  }
  return camera;
}

Vec3 OnSphere(double azimuth, double z) {
  const double ring = std::sqrt(std::max(0.0, 1.0 - z * z));
  return Vec3{ring * std::cos(azimuth), ring * std::sin(azimuth), z} * kBuiltinCameraDistance;
}

std::vector<Vec3> CameraPositions(const std::string& split, int count, uint32_t seed) {
  std::vector<Vec3> positions;
  Random random(0x5eed0000ull ^ (uint64_t{seed} << 16) ^
                (split == "train"  ? 1
                 : split == "test" ? 2
                                   : 3));
  if (split == "train") {
    // Uniform in area over the band; the poles are left out because the look-at frame needs
    // a horizon and nothing is seen from straight below the slab.
    for (int i = 0; i < count; ++i) {
      const double azimuth = 2 * kPi * random.Uniform();
      const double z = 0.1 + 0.85 * random.Uniform();
      positions.push_back(OnSphere(azimuth, z));
    }
  } else {
    const double elevation = (split == "test" ? 30.0 : 50.0) * kPi / 180.0;
    const double phase = 2 * kPi * random.Uniform();
    for (int i = 0; i < count; ++i) {
      positions.push_back(OnSphere(phase + 2 * kPi * i / count, std::sin(elevation)));
    }
  }
  return positions;
}

Image Render(const Camera& camera) {
  static const double kSubpixel[4][2] = {
      {-0.25, -0.25}, {0.25, -0.25}, {-0.25, 0.25}, {0.25, 0.25}};
  Image image = MakeImage(camera.width, camera.height, 3);
  for (int j = 0; j < camera.height; ++j) {
    for (int i = 0; i < camera.width; ++i) {
      Vec3 sum;
      for (const auto& offset : kSubpixel) {
        float origin[3], dir[3];
        GenerateRay(camera, i + offset[0], j + offset[1], origin, dir);
        sum = sum + Shade({origin[0], origin[1], origin[2]}, Normalized({dir[0], dir[1], dir[2]}));
      }
      image.at(i, j, 0) = static_cast<float>(sum.x * 0.25);
      image.at(i, j, 1) = static_cast<float>(sum.y * 0.25);
      image.at(i, j, 2) = static_cast<float>(sum.z * 0.25);
    }
  }
  return image;
}

}  // namespace

Dataset MakeBuiltinScene(const std::string& split, int width, int height, int num_views,
                         uint32_t seed) {
  procedural::CheckSceneArguments("builtin", split, width, height);
  if (num_views < 1) {
    throw std::runtime_error("builtin scene: num_views must be >= 1, got " +
                             std::to_string(num_views));
  }
  const std::vector<Vec3> positions = CameraPositions(split, num_views, seed);
  Dataset dataset;  // defaults are the Blender conventions
  dataset.views.resize(num_views);
#pragma omp parallel for schedule(dynamic)
  for (int v = 0; v < num_views; ++v) {
    View& view = dataset.views[v];
    view.camera = LookAtOrigin(positions[v], width, height);
    view.rgb = Render(view.camera);
    char name[64];
    std::snprintf(name, sizeof name, "builtin/%s_%03d", split.c_str(), v);
    view.name = name;
  }
  return dataset;
}

}  // namespace ecrf::trainer
