#include "trainer/data/llff.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "trainer/data/npy.h"

namespace ecrf::trainer {
namespace {

namespace fs = std::filesystem;

constexpr int kColumns = 17;
// NeRF's llffhold and bd_factor.
constexpr int kTestEvery = 8;
constexpr double kBoundFactor = 0.75;
// NeRF samples from 0.9 x the nearest bound (without NDC).
constexpr double kNearMargin = 0.9;
// Image sizes may differ from hwf * scale by rounding when images_N were made.
constexpr double kAspectTolerance = 0.01;
// Camera centres farther from the origin than this, in the units where the nearest bound is
// 1 / kBoundFactor, mean bounds that do not belong to the poses (real captures: below 10).
constexpr double kMaxScaledCameraDistance = 1e4;

using Mat34 = double[3][4];

void Normalize(double v[3]) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  for (int a = 0; a < 3; ++a) v[a] /= n;
}

void Cross(const double a[3], const double b[3], double out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

// NeRF's poses_avg: mean centre, mean back axis, mean up axis, made orthonormal.
void AveragePose(const std::vector<Camera>& cameras, Mat34 avg) {
  double centre[3] = {0, 0, 0}, back[3] = {0, 0, 0}, up[3] = {0, 0, 0};
  for (const Camera& c : cameras) {
    for (int a = 0; a < 3; ++a) {
      centre[a] += c.c2w[a][3] / cameras.size();
      back[a] += c.c2w[a][2];
      up[a] += c.c2w[a][1];
    }
  }
  Normalize(back);
  double right[3], true_up[3];
  Cross(up, back, right);
  Normalize(right);
  Cross(back, right, true_up);
  Normalize(true_up);
  for (int a = 0; a < 3; ++a) {
    avg[a][0] = right[a];
    avg[a][1] = true_up[a];
    avg[a][2] = back[a];
    avg[a][3] = centre[a];
  }
}

// camera = inverse(avg) * camera, for rigid avg.
void Recentre(const Mat34 avg, Camera* camera) {
  double out[3][4];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      double v = 0;
      for (int k = 0; k < 3; ++k) v += avg[k][r] * (camera->c2w[k][c] - (c == 3 ? avg[k][3] : 0.0));
      out[r][c] = v;
    }
  }
  std::copy(&out[0][0], &out[0][0] + 12, &camera->c2w[0][0]);
}

bool IsImageName(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

std::vector<fs::path> SortedImages(const fs::path& folder) {
  std::vector<fs::path> images;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(folder, error)) {
    if (!IsImageName(entry.path())) continue;
    std::error_code status;
    const bool regular = entry.is_regular_file(status);
    // An image name that cannot be followed (a symlink loop, no permission) is an error, not a
    // file to leave out: the poses match the images by position.
    if (status) throw std::runtime_error(entry.path().string() + ": " + status.message());
    if (regular) images.push_back(entry.path());
  }
  if (error) throw std::runtime_error(folder.string() + ": cannot list: " + error.message());
  std::sort(images.begin(), images.end());
  return images;
}

void Grow(double box[2][3], const double p[3]) {
  for (int a = 0; a < 3; ++a) {
    box[0][a] = std::min(box[0][a], p[a]);
    box[1][a] = std::max(box[1][a], p[a]);
  }
}

// Corner rays of the image at depths `near` and `far` along the viewing axis (LLFF bounds are
// z depths), and the camera centre.
void GrowByFrustum(const Camera& camera, double near, double far, double box[2][3]) {
  const double centre[3] = {camera.c2w[0][3], camera.c2w[1][3], camera.c2w[2][3]};
  Grow(box, centre);
  for (int corner = 0; corner < 4; ++corner) {
    const double x = ((corner & 1) ? camera.width : 0) - camera.cx;
    const double y = ((corner & 2) ? camera.height : 0) - camera.cy;
    const double local[3] = {x / camera.fx, -y / camera.fy, -1.0};
    for (double depth : {near, far}) {
      double p[3];
      for (int r = 0; r < 3; ++r) {
        p[r] = camera.c2w[r][3];
        for (int k = 0; k < 3; ++k) p[r] += camera.c2w[r][k] * local[k] * depth;
      }
      Grow(box, p);
    }
  }
}

// The least shrinking on load: images_<downscale>, else the images_<k> of the largest factor k
// of downscale that is there (the published LLFF sets ship images_4 and images_8 but not always
// the full-size images), shrunk by downscale / k on load; else the full-size images.
fs::path ImagesFolder(const fs::path& root, int downscale, int* prescaled) {
  std::error_code error;
  for (int k = downscale; k > 1; --k) {
    const fs::path copies = root / ("images_" + std::to_string(k));
    if (downscale % k == 0 && fs::is_directory(copies, error)) {
      *prescaled = k;
      return copies;
    }
  }
  *prescaled = 1;
  return root / "images";
}

}  // namespace

DatasetManifest ReadLlffManifest(const std::string& dir, const std::string& split, int downscale,
                                 int* prescaled) {
  const fs::path root(dir);
  const std::string npy_path = (root / "poses_bounds.npy").string();
  const NpyMatrix table = ReadNpyMatrix(npy_path);
  auto fail = [&](const std::string& problem) {
    throw std::runtime_error(npy_path + ": " + problem);
  };
  if (table.cols != kColumns || table.rows < 1) {
    fail("shape is " + std::to_string(table.rows) + " x " + std::to_string(table.cols) +
         "; need N x 17 (N >= 1)");
  }
  for (int64_t r = 0; r < table.rows; ++r) {
    for (int64_t c = 0; c < kColumns; ++c) {
      if (!std::isfinite(table.at(r, c))) {
        fail("row " + std::to_string(r) + ", column " + std::to_string(c) + " is not finite");
      }
    }
  }

  const fs::path folder = ImagesFolder(root, downscale, prescaled);
  std::error_code error;
  if (!fs::is_directory(folder, error))
    throw std::runtime_error(folder.string() + ": no such directory (LLFF images)");
  const std::vector<fs::path> images = SortedImages(folder);
  if (int64_t(images.size()) != table.rows) {
    fail(std::to_string(table.rows) + " poses but " + folder.string() + " has " +
         std::to_string(images.size()) +
         " images (.png/.jpg); they must match one to one in name order");
  }

  std::vector<Camera> cameras(size_t(table.rows));
  double min_bound = INFINITY, max_bound = 0;
  for (int64_t i = 0; i < table.rows; ++i) {
    auto m = [&](int r, int c) { return table.at(i, r * 5 + c); };
    const double height = m(0, 4), width = m(1, 4), focal = m(2, 4);
    const double near = table.at(i, 15), far = table.at(i, 16);
    if (!(height > 0 && width > 0 && focal > 0))
      fail("row " + std::to_string(i) + ": h, w and focal must be positive");
    if (!(near > 0 && far >= near))
      fail("row " + std::to_string(i) + ": bounds need 0 < near <= far");
    min_bound = std::min(min_bound, near);
    max_bound = std::max(max_bound, far);
    Camera& camera = cameras[size_t(i)];
    // [down, right, back] columns to OpenGL [right, up, back]: NeRF's
    // concatenate([poses[:, 1:2], -poses[:, 0:1], poses[:, 2:]]).
    for (int r = 0; r < 3; ++r) {
      camera.c2w[r][0] = m(r, 1);
      camera.c2w[r][1] = -m(r, 0);
      camera.c2w[r][2] = m(r, 2);
      camera.c2w[r][3] = m(r, 3);
    }
    const ImageSize size = ReadImageSize(images[size_t(i)].string());
    if (std::abs(double(size.height) / size.width - height / width) >
        kAspectTolerance * height / width) {
      throw std::runtime_error(images[size_t(i)].string() + ": image is " +
                               std::to_string(size.width) + "x" + std::to_string(size.height) +
                               " but row " + std::to_string(i) + " of " + npy_path + " says " +
                               std::to_string(int(width)) + "x" + std::to_string(int(height)));
    }
    camera.width = size.width;
    camera.height = size.height;
    camera.fx = camera.fy = focal * size.width / width;
    camera.cx = 0.5 * size.width;
    camera.cy = 0.5 * size.height;
    // The same checks as the JSON loaders, on the pose as given (the axis turn above keeps
    // orthonormality and the sign of det).
    for (const std::string& problem : {PoseProblem(camera.c2w), IntrinsicsProblem(camera)}) {
      if (!problem.empty()) fail("row " + std::to_string(i) + ": " + problem);
    }
  }

  const double scale = 1.0 / (min_bound * kBoundFactor);
  for (size_t i = 0; i < cameras.size(); ++i) {
    Camera& camera = cameras[i];
    for (int r = 0; r < 3; ++r) camera.c2w[r][3] *= scale;
    // In units of the nearest bound the cameras sit within a few scene sizes of each other; a
    // bound of 1e-300 would put them at infinity.
    const double distance =
        std::sqrt(camera.c2w[0][3] * camera.c2w[0][3] + camera.c2w[1][3] * camera.c2w[1][3] +
                  camera.c2w[2][3] * camera.c2w[2][3]);
    if (!(distance <= kMaxScaledCameraDistance)) {
      char text[200];
      std::snprintf(
          text, sizeof(text),
          "row %zu: scaled so that the nearest bound (%g) is 1/0.75, the camera lies %.3g "
          "from the origin (at most %g): the bounds do not fit the poses",
          i, min_bound, distance, kMaxScaledCameraDistance);
      fail(text);
    }
  }
  Mat34 avg;
  AveragePose(cameras, avg);
  for (Camera& camera : cameras) Recentre(avg, &camera);

  DatasetManifest manifest;
  manifest.white_background = false;
  manifest.near = kNearMargin * min_bound * scale;
  manifest.far = max_bound * scale;
  double box[2][3] = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
  for (int64_t i = 0; i < table.rows; ++i) {
    GrowByFrustum(cameras[size_t(i)], table.at(i, 15) * scale, table.at(i, 16) * scale, box);
    if ((i % kTestEvery == 0) != (split != "train")) continue;
    ViewSource source;
    source.camera = cameras[size_t(i)];
    source.image_path = images[size_t(i)].string();
    source.name = images[size_t(i)].stem().string();
    manifest.views.push_back(std::move(source));
  }
  std::copy(&box[0][0], &box[0][0] + 6, &manifest.scene_aabb[0][0]);
  if (manifest.views.empty())
    fail("no images for split '" + split + "' (" + std::to_string(table.rows) + " in all)");
  return manifest;
}

}  // namespace ecrf::trainer
