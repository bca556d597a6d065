#include "tools/prepare/colmap_model.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

namespace ecrf {
namespace tools {
namespace {

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(line);
  }
  return lines;
}

bool IsBlank(const std::string& line) { return line.find_first_not_of(" \t") == std::string::npos; }

[[noreturn]] void Fail(const std::string& where, size_t line, const std::string& what) {
  throw std::runtime_error(where + ":" + std::to_string(line + 1) + ": " + what);
}

// Whitespace-separated words; numbers are checked where they are used.
std::vector<std::string> Words(const std::string& line) {
  std::vector<std::string> words;
  std::istringstream in(line);
  std::string w;
  while (in >> w) words.push_back(w);
  return words;
}

double Number(const std::string& word, const std::string& where, size_t line, const char* what) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(word, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != word.size() || !std::isfinite(v)) {
    Fail(where, line, std::string(what) + " '" + word + "' is not a finite number");
  }
  return v;
}

int Integer(const std::string& word, const std::string& where, size_t line, const char* what) {
  const double v = Number(word, where, line, what);
  if (v != std::floor(v) || v < 0 || v > 1e9) {
    Fail(where, line, std::string(what) + " '" + word + "' is not a non-negative integer");
  }
  return int(v);
}

// Parameter count of a supported model; -1 for the others.
int ParamCount(const std::string& model) {
  const std::vector<std::string> names = trainer::TypedNames<ColmapCameraModel>();
  for (size_t k = 0; k < names.size(); ++k) {
    if (model == names[k]) return kColmapParamCount[k];
  }
  return -1;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open (" + std::strerror(errno) + ")");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void Cross(const double a[3], const double b[3], double out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

double Dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Solves the symmetric 3x3 system A x = b by Cramer's rule; false when A is near singular
// relative to its size.
bool Solve3(const double A[3][3], const double b[3], double x[3]) {
  const double det = A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
                     A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
                     A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
  double norm = 0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) norm = std::max(norm, std::fabs(A[r][c]));
  if (!(std::fabs(det) > 1e-6 * norm * norm * norm)) return false;
  for (int k = 0; k < 3; ++k) {
    double M[3][3];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) M[r][c] = c == k ? b[r] : A[r][c];
    x[k] = (M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) -
            M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
            M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0])) /
           det;
  }
  return true;
}

}  // namespace

std::map<int, ColmapCamera> ParseColmapCameras(const std::string& text, const std::string& where) {
  std::map<int, ColmapCamera> cameras;
  const std::vector<std::string> lines = Lines(text);
  for (size_t i = 0; i < lines.size(); ++i) {
    if (IsBlank(lines[i]) || lines[i][lines[i].find_first_not_of(" \t")] == '#') continue;
    const std::vector<std::string> w = Words(lines[i]);
    if (w.size() < 4) Fail(where, i, "expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS");
    const int id = Integer(w[0], where, i, "camera id");
    ColmapCamera c;
    c.model = w[1];
    const int count = ParamCount(c.model);
    if (count < 0) {
      Fail(where, i,
           "camera model " + c.model + " is not supported (" +
               trainer::NameList<ColmapCameraModel>() + ": the distortion the trainer models)");
    }
    if (int(w.size()) != 4 + count) {
      Fail(where, i,
           c.model + " needs " + std::to_string(count) + " parameters, the line has " +
               std::to_string(int(w.size()) - 4));
    }
    c.width = Integer(w[2], where, i, "width");
    c.height = Integer(w[3], where, i, "height");
    if (c.width < 1 || c.height < 1) Fail(where, i, "the image size must be positive");
    double p[8];
    for (int k = 0; k < count; ++k) p[k] = Number(w[size_t(4 + k)], where, i, "parameter");
    const bool one_focal =
        c.model == "SIMPLE_PINHOLE" || c.model == "SIMPLE_RADIAL" || c.model == "RADIAL";
    c.fx = p[0];
    c.fy = one_focal ? p[0] : p[1];
    c.cx = one_focal ? p[1] : p[2];
    c.cy = one_focal ? p[2] : p[3];
    if (c.model == "SIMPLE_RADIAL") c.k1 = p[3];
    if (c.model == "RADIAL") c.k1 = p[3], c.k2 = p[4];
    if (c.model == "OPENCV") c.k1 = p[4], c.k2 = p[5], c.p1 = p[6], c.p2 = p[7];
    if (!(c.fx > 0 && c.fy > 0)) Fail(where, i, "the focal length must be positive");
    if (!cameras.emplace(id, c).second) Fail(where, i, "camera id " + w[0] + " appears twice");
  }
  return cameras;
}

std::vector<ColmapImage> ParseColmapImages(const std::string& text, const std::string& where) {
  std::vector<ColmapImage> images;
  const std::vector<std::string> lines = Lines(text);
  for (size_t i = 0; i < lines.size(); ++i) {
    // Each image is two lines: the pose, then its 2-D points (which may be empty).
    if (IsBlank(lines[i]) || lines[i][lines[i].find_first_not_of(" \t")] == '#') continue;
    const std::vector<std::string> w = Words(lines[i]);
    if (w.size() < 10) {
      Fail(where, i, "expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME");
    }
    double q[4], t[3];
    for (int k = 0; k < 4; ++k) q[k] = Number(w[size_t(1 + k)], where, i, "quaternion");
    for (int k = 0; k < 3; ++k) t[k] = Number(w[size_t(5 + k)], where, i, "translation");
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(std::fabs(norm - 1.0) < 1e-3)) Fail(where, i, "the rotation is not a unit quaternion");
    for (double& v : q) v /= norm;
    ColmapImage image;
    image.camera_id = Integer(w[8], where, i, "camera id");
    // The name is the rest of the line: COLMAP keeps spaces in file names.
    size_t pos = 0;
    for (int k = 0; k < 9; ++k) {
      pos = lines[i].find_first_not_of(" \t", pos);
      pos = lines[i].find_first_of(" \t", pos);
    }
    image.name = lines[i].substr(lines[i].find_first_not_of(" \t", pos));
    while (!image.name.empty() && (image.name.back() == ' ' || image.name.back() == '\t'))
      image.name.pop_back();
    const double w0 = q[0], x = q[1], y = q[2], z = q[3];
    const double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w0 * z), 2 * (x * z + w0 * y)},
                            {2 * (x * y + w0 * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w0 * x)},
                            {2 * (x * z - w0 * y), 2 * (y * z + w0 * x), 1 - 2 * (x * x + y * y)}};
    // c2w = [R^T | -R^T t], then the camera's y and z axes flip (OpenCV -> OpenGL).
    for (int r = 0; r < 3; ++r) {
      image.c2w[r][0] = R[0][r];
      image.c2w[r][1] = -R[1][r];
      image.c2w[r][2] = -R[2][r];
      image.c2w[r][3] = -(R[0][r] * t[0] + R[1][r] * t[1] + R[2][r] * t[2]);
    }
    images.push_back(image);
    ++i;  // the points line
  }
  return images;
}

ColmapModel ReadColmapTextModel(const std::string& dir) {
  ColmapModel model;
  const std::string cameras = dir + "/cameras.txt", images = dir + "/images.txt";
  model.cameras = ParseColmapCameras(ReadFile(cameras), cameras);
  model.images = ParseColmapImages(ReadFile(images), images);
  for (const ColmapImage& image : model.images) {
    if (!model.cameras.count(image.camera_id)) {
      throw std::runtime_error(images + ": image " + image.name + " names camera " +
                               std::to_string(image.camera_id) + ", which " + cameras +
                               " does not list");
    }
  }
  return model;
}

void ColmapPoseFromC2w(const double c2w[3][4], double qvec[4], double tvec[3]) {
  // World-to-camera rotation: rows are the OpenCV camera axes (x, -y_gl, -z_gl) in world space.
  double R[3][3];
  for (int c = 0; c < 3; ++c) {
    R[0][c] = c2w[c][0];
    R[1][c] = -c2w[c][1];
    R[2][c] = -c2w[c][2];
  }
  for (int r = 0; r < 3; ++r)
    tvec[r] = -(R[r][0] * c2w[0][3] + R[r][1] * c2w[1][3] + R[r][2] * c2w[2][3]);
  const double trace = R[0][0] + R[1][1] + R[2][2];
  double w, x, y, z;
  if (trace > 0) {
    const double s = 2 * std::sqrt(trace + 1);
    w = s / 4, x = (R[2][1] - R[1][2]) / s, y = (R[0][2] - R[2][0]) / s,
    z = (R[1][0] - R[0][1]) / s;
  } else if (R[0][0] > R[1][1] && R[0][0] > R[2][2]) {
    const double s = 2 * std::sqrt(1 + R[0][0] - R[1][1] - R[2][2]);
    w = (R[2][1] - R[1][2]) / s, x = s / 4, y = (R[0][1] + R[1][0]) / s,
    z = (R[0][2] + R[2][0]) / s;
  } else if (R[1][1] > R[2][2]) {
    const double s = 2 * std::sqrt(1 + R[1][1] - R[0][0] - R[2][2]);
    w = (R[0][2] - R[2][0]) / s, x = (R[0][1] + R[1][0]) / s, y = s / 4,
    z = (R[1][2] + R[2][1]) / s;
  } else {
    const double s = 2 * std::sqrt(1 + R[2][2] - R[0][0] - R[1][1]);
    w = (R[1][0] - R[0][1]) / s, x = (R[0][2] + R[2][0]) / s, y = (R[1][2] + R[2][1]) / s,
    z = s / 4;
  }
  const double sign = w < 0 ? -1 : 1;  // COLMAP's convention: w >= 0
  qvec[0] = sign * w, qvec[1] = sign * x, qvec[2] = sign * y, qvec[3] = sign * z;
}

double NormalizeColmapPoses(std::vector<ColmapImage>* images, double mean_distance) {
  if (images->empty()) return 1.0;
  // 1. Rotate the mean up vector (each camera's +y, OpenGL) onto +z (Rodrigues).
  double up[3] = {0, 0, 0};
  for (const ColmapImage& im : *images)
    for (int a = 0; a < 3; ++a) up[a] += im.c2w[a][1];
  const double up_norm = std::sqrt(Dot(up, up));
  double rot[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  if (up_norm > 0) {
    for (double& v : up) v /= up_norm;
    const double zaxis[3] = {0, 0, 1};
    double axis[3];
    Cross(up, zaxis, axis);
    const double s = std::sqrt(Dot(axis, axis)), c = Dot(up, zaxis);
    if (s > 1e-12) {
      const double K[3][3] = {
          {0, -axis[2], axis[1]}, {axis[2], 0, -axis[0]}, {-axis[1], axis[0], 0}};
      double K2[3][3];
      for (int r = 0; r < 3; ++r)
        for (int col = 0; col < 3; ++col) {
          K2[r][col] = 0;
          for (int k = 0; k < 3; ++k) K2[r][col] += K[r][k] * K[k][col];
        }
      // R = I + K + K^2 (1 - c) / s^2, K built from the unnormalised axis (|axis| = s).
      for (int r = 0; r < 3; ++r)
        for (int col = 0; col < 3; ++col)
          rot[r][col] = (r == col ? 1.0 : 0.0) + K[r][col] + K2[r][col] * (1 - c) / (s * s);
    } else if (c < 0) {
      rot[1][1] = -1, rot[2][2] = -1;  // up is -z: turn half a turn about x
    }
  }
  for (ColmapImage& im : *images) {
    double m[3][4];
    for (int r = 0; r < 3; ++r)
      for (int col = 0; col < 4; ++col)
        m[r][col] =
            rot[r][0] * im.c2w[0][col] + rot[r][1] * im.c2w[1][col] + rot[r][2] * im.c2w[2][col];
    std::copy(&m[0][0], &m[0][0] + 12, &im.c2w[0][0]);
  }
  // 2. The point nearest every optical axis (least squares: sum (I - d d^T)(p - o) = 0); the
  // mean camera centre where the axes are near parallel (a forward-facing capture).
  double A[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}, b[3] = {0, 0, 0}, mean[3] = {0, 0, 0};
  for (const ColmapImage& im : *images) {
    const double d[3] = {-im.c2w[0][2], -im.c2w[1][2], -im.c2w[2][2]};
    const double o[3] = {im.c2w[0][3], im.c2w[1][3], im.c2w[2][3]};
    for (int r = 0; r < 3; ++r) {
      mean[r] += o[r] / double(images->size());
      for (int c = 0; c < 3; ++c) {
        const double p = (r == c ? 1.0 : 0.0) - d[r] * d[c];
        A[r][c] += p;
        b[r] += p * o[c];
      }
    }
  }
  double centre[3];
  if (images->size() < 2 || !Solve3(A, b, centre)) std::copy(mean, mean + 3, centre);
  // 3. Scale to the mean distance.
  double sum = 0;
  for (ColmapImage& im : *images) {
    for (int a = 0; a < 3; ++a) im.c2w[a][3] -= centre[a];
    const double o[3] = {im.c2w[0][3], im.c2w[1][3], im.c2w[2][3]};
    sum += std::sqrt(Dot(o, o));
  }
  const double mean_len = sum / double(images->size());
  const double scale = mean_len > 0 ? mean_distance / mean_len : 1.0;
  for (ColmapImage& im : *images)
    for (int a = 0; a < 3; ++a) im.c2w[a][3] *= scale;
  return scale;
}

std::string TransformsJson(const ColmapModel& model, const std::vector<ColmapImage>& images,
                           int aabb_scale, const std::string& image_dir) {
  using Json = nlohmann::ordered_json;
  auto intrinsics = [&](const ColmapCamera& c, Json* out) {
    (*out)["camera_model"] =
        c.k1 == 0 && c.k2 == 0 && c.p1 == 0 && c.p2 == 0 ? "PINHOLE" : "OPENCV";
    (*out)["fl_x"] = c.fx;
    (*out)["fl_y"] = c.fy;
    (*out)["cx"] = c.cx;
    (*out)["cy"] = c.cy;
    (*out)["w"] = c.width;
    (*out)["h"] = c.height;
    (*out)["k1"] = c.k1;
    (*out)["k2"] = c.k2;
    (*out)["p1"] = c.p1;
    (*out)["p2"] = c.p2;
  };
  bool shared = true;
  for (const ColmapImage& im : images) shared = shared && im.camera_id == images[0].camera_id;
  Json root = Json::object();
  if (shared && !images.empty()) intrinsics(model.cameras.at(images[0].camera_id), &root);
  root["aabb_scale"] = aabb_scale;
  std::vector<const ColmapImage*> sorted;
  for (const ColmapImage& im : images) sorted.push_back(&im);
  std::sort(sorted.begin(), sorted.end(),
            [](const ColmapImage* a, const ColmapImage* b) { return a->name < b->name; });
  Json frames = Json::array();
  for (const ColmapImage* im : sorted) {
    Json frame = Json::object();
    frame["file_path"] = image_dir + "/" + im->name;
    if (!shared) intrinsics(model.cameras.at(im->camera_id), &frame);
    Json matrix = Json::array();
    for (int r = 0; r < 3; ++r)
      matrix.push_back({im->c2w[r][0], im->c2w[r][1], im->c2w[r][2], im->c2w[r][3]});
    matrix.push_back({0.0, 0.0, 0.0, 1.0});
    frame["transform_matrix"] = matrix;
    frames.push_back(frame);
  }
  root["frames"] = frames;
  return root.dump(2) + "\n";
}

}  // namespace tools
}  // namespace ecrf
