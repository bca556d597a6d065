#include "trainer/data/dataset.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <utility>

#include <nlohmann/json.hpp>

#include "trainer/data/file_io.h"
#include "trainer/data/llff.h"

namespace ecrf::trainer {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

enum class Layout { kBlender, kNgp };

// NeRF/LLFF hold-out convention for captures that ship a single transforms.json.
constexpr int kNgpTestEvery = 8;

// Keeps samples off the lens when a camera sits inside the box (as a fraction of its diagonal).
constexpr double kMinNearFraction = 0.01;

// "what, where, why" errors for one JSON file.
class JsonContext {
 public:
  explicit JsonContext(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void Fail(const std::string& problem) const {
    throw std::runtime_error(file_ + ": " + problem);
  }
  // Names the frame by its index and, when it has one, its file_path.
  [[noreturn]] void FailFrame(size_t frame, const std::string& problem) const {
    std::string where = "frame " + std::to_string(frame);
    if (frames_ && frame < frames_->size() && (*frames_)[frame].is_object()) {
      auto it = (*frames_)[frame].find("file_path");
      if (it != (*frames_)[frame].end() && it->is_string())
        where += " ('" + it->get<std::string>() + "')";
    }
    Fail(where + ": " + problem);
  }
  void set_frames(const json* frames) { frames_ = frames; }
  const std::string& file() const { return file_; }

 private:
  std::string file_;
  const json* frames_ = nullptr;
};

std::optional<double> OptionalNumber(const json& object, const char* key, const std::string& where,
                                     const JsonContext& context) {
  auto it = object.find(key);
  if (it == object.end() || it->is_null()) return std::nullopt;
  if (!it->is_number()) context.Fail(where + "'" + key + "' must be a number");
  return it->get<double>();
}

// Intrinsics may sit at the top level or in each frame (nerfstudio with several cameras);
// the frame's value wins.
struct IntrinsicFields {
  std::optional<double> fl_x, fl_y, cx, cy, angle_x, angle_y, w, h, k1, k2, p1, p2;

  void ReadFrom(const json& object, const std::string& where, const JsonContext& context) {
    auto read = [&](std::optional<double>& field, const char* key) {
      if (auto value = OptionalNumber(object, key, where, context)) field = value;
    };
    read(fl_x, "fl_x");
    read(fl_y, "fl_y");
    read(cx, "cx");
    read(cy, "cy");
    read(angle_x, "camera_angle_x");
    read(angle_y, "camera_angle_y");
    read(w, "w");
    read(h, "h");
    read(k1, "k1");
    read(k2, "k2");
    read(p1, "p1");
    read(p2, "p2");
    for (const char* key : {"k3", "k4"}) {
      auto value = OptionalNumber(object, key, where, context);
      if (value && *value != 0.0) {
        context.Fail(where + "'" + key + "' is not supported (only k1 k2 p1 p2 distortion)");
      }
    }
    auto model = object.find("camera_model");
    if (model != object.end()) {
      if (!model->is_string()) context.Fail(where + "'camera_model' must be a string");
      const std::string name = model->get<std::string>();
      if (name != "OPENCV" && name != "PINHOLE" && name != "SIMPLE_PINHOLE") {
        context.Fail(where + "camera_model '" + name +
                     "' is not supported (need OPENCV or PINHOLE)");
      }
    }
  }
};

void ReadTransform(const json& frame, size_t index, const JsonContext& context, Camera* camera) {
  auto it = frame.find("transform_matrix");
  if (it == frame.end()) context.FailFrame(index, "missing 'transform_matrix'");
  const json& matrix = *it;
  bool ok = matrix.is_array() && matrix.size() == 4;
  for (size_t r = 0; ok && r < 4; ++r) {
    ok = matrix[r].is_array() && matrix[r].size() == 4;
    for (size_t c = 0; ok && c < 4; ++c) ok = matrix[r][c].is_number();
  }
  if (!ok) context.FailFrame(index, "'transform_matrix' is not a 4x4 array of numbers");
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      camera->c2w[r][c] = matrix[r][c].get<double>();
      if (!std::isfinite(camera->c2w[r][c]))
        context.FailFrame(index, "'transform_matrix' has a non-finite entry");
    }
  }
  const std::string problem = PoseProblem(camera->c2w);
  if (!problem.empty()) context.FailFrame(index, "'transform_matrix': " + problem);
}

std::string StripDotSlash(std::string path) {
  while (path.rfind("./", 0) == 0) path.erase(0, 2);
  return path;
}

// file_path usually omits the extension (Blender: ".png"); keep one if given.
std::string ResolveImagePath(const fs::path& dir, const std::string& file_path) {
  fs::path path = dir / StripDotSlash(file_path);
  if (path.has_extension()) return path.string();
  for (const char* extension : {".png", ".jpg", ".jpeg", ".PNG", ".JPG", ".JPEG"}) {
    fs::path candidate = path;
    candidate += extension;
    std::error_code error;
    if (fs::is_regular_file(candidate, error)) return candidate.string();
  }
  fs::path fallback = path;
  fallback += ".png";
  return fallback.string();
}

std::string ViewName(const std::string& file_path) {
  fs::path name = StripDotSlash(file_path);
  if (name.has_extension()) name.replace_extension();
  return name.generic_string();
}

Camera ResolveIntrinsics(const IntrinsicFields& fields, const std::string& image_path, size_t index,
                         const JsonContext& context, Camera camera) {
  if (fields.w && fields.h) {
    camera.width = static_cast<int>(std::lround(*fields.w));
    camera.height = static_cast<int>(std::lround(*fields.h));
    if (camera.width <= 0 || camera.height <= 0)
      context.FailFrame(index, "'w' and 'h' must be positive");
  } else {
    // Blender JSON leaves the size to the image; its header is enough.
    ImageSize size = ReadImageSize(image_path);
    camera.width = size.width;
    camera.height = size.height;
  }
  if (fields.fl_x) {
    camera.fx = *fields.fl_x;
  } else if (fields.angle_x) {
    camera.fx = FocalFromFieldOfView(camera.width, *fields.angle_x);
  } else {
    context.FailFrame(index, "no focal length: need 'fl_x' or 'camera_angle_x'");
  }
  if (fields.fl_y) {
    camera.fy = *fields.fl_y;
  } else if (fields.angle_y) {
    camera.fy = FocalFromFieldOfView(camera.height, *fields.angle_y);
  } else {
    camera.fy = camera.fx;  // square pixels
  }
  camera.cx = fields.cx.value_or(0.5 * camera.width);
  camera.cy = fields.cy.value_or(0.5 * camera.height);
  camera.k1 = fields.k1.value_or(0.0);
  camera.k2 = fields.k2.value_or(0.0);
  camera.p1 = fields.p1.value_or(0.0);
  camera.p2 = fields.p2.value_or(0.0);
  // Finite, positive and in range: the one camera check every loader applies.
  const std::string problem = IntrinsicsProblem(camera);
  if (!problem.empty()) context.FailFrame(index, "intrinsics: " + problem);
  return camera;
}

json ReadJson(const std::string& path) {
  const std::vector<uint8_t> bytes = ReadWholeFile(path);  // regular files only
  try {
    return json::parse(bytes.begin(), bytes.end());
  } catch (const json::exception& error) {  // parse_error, and out_of_range for numbers like 1e999
    throw std::runtime_error(path + ": invalid JSON: " + error.what());
  }
}

void SetNgpAabb(const json& root, const JsonContext& context, DatasetManifest* manifest) {
  const double aabb_scale = OptionalNumber(root, "aabb_scale", "", context).value_or(1.0);
  const double scale = OptionalNumber(root, "scale", "", context).value_or(kNgpDefaultScale);
  if (!(aabb_scale > 0) || !(scale > 0)) context.Fail("'aabb_scale' and 'scale' must be positive");
  double offset[3] = {kNgpDefaultOffset[0], kNgpDefaultOffset[1], kNgpDefaultOffset[2]};
  if (auto it = root.find("offset"); it != root.end()) {
    if (!it->is_array() || it->size() != 3 || !(*it)[0].is_number() || !(*it)[1].is_number() ||
        !(*it)[2].is_number()) {
      context.Fail("'offset' must be an array of 3 numbers");
    }
    for (int a = 0; a < 3; ++a) offset[a] = (*it)[a].get<double>();
  }
  NgpAabb(aabb_scale, scale, offset, manifest->scene_aabb);
}

void SetNearFarFromCameras(const std::vector<Camera>& cameras, DatasetManifest* manifest) {
  NearFarFromCameras(cameras, manifest->scene_aabb, &manifest->near, &manifest->far);
}

std::string FilePathOf(const json& frame, size_t index, const JsonContext& context) {
  auto it = frame.find("file_path");
  if (it == frame.end()) context.FailFrame(index, "missing 'file_path'");
  if (!it->is_string() || it->get<std::string>().empty()) {
    context.FailFrame(index, "'file_path' must be a non-empty string");
  }
  return it->get<std::string>();
}

// The non-empty `frames` array of a transforms file, every entry an object; its top-level
// intrinsics go into `shared`.
const json& TransformFrames(const json& root, JsonContext* context, IntrinsicFields* shared) {
  if (!root.is_object()) context->Fail("top level must be a JSON object");
  shared->ReadFrom(root, "", *context);
  auto frames_it = root.find("frames");
  if (frames_it == root.end()) context->Fail("missing 'frames'");
  if (!frames_it->is_array()) context->Fail("'frames' must be an array");
  const json& frames = *frames_it;
  if (frames.empty()) context->Fail("'frames' is empty");
  context->set_frames(&frames);
  for (size_t i = 0; i < frames.size(); ++i) {
    if (!frames[i].is_object()) context->FailFrame(i, "must be a JSON object");
  }
  return frames;
}

DatasetManifest ParseTransforms(const fs::path& dir, const std::string& json_path, Layout layout,
                                const std::string& split) {
  JsonContext context(json_path);
  const json root = ReadJson(json_path);
  IntrinsicFields shared;
  const json& frames = TransformFrames(root, &context, &shared);

  DatasetManifest manifest;
  std::vector<size_t> order(frames.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  if (layout == Layout::kNgp) {
    SetNgpAabb(root, context, &manifest);
    if (auto it = root.find("white_transparent"); it != root.end()) {
      if (!it->is_boolean()) context.Fail("'white_transparent' must be true or false");
      manifest.white_background = it->get<bool>();
    } else {
      manifest.white_background = false;  // LoadDataset sets it if any image has alpha
    }
    // Sorting makes the hold-out independent of the order tools happened to write frames in.
    std::vector<std::string> paths(frames.size());
    for (size_t i = 0; i < frames.size(); ++i) paths[i] = FilePathOf(frames[i], i, context);
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return paths[a] < paths[b]; });
  }

  std::vector<Camera> poses;  // every frame's pose, for near/far independent of the split
  size_t skipped = 0;
  for (size_t rank = 0; rank < order.size(); ++rank) {
    const size_t index = order[rank];
    const json& frame = frames[index];
    Camera camera;
    ReadTransform(frame, index, context, &camera);
    poses.push_back(camera);
    if (layout == Layout::kNgp) {
      const bool is_test = rank % kNgpTestEvery == 0;
      if (is_test != (split != "train")) continue;
    }
    const std::string file_path = FilePathOf(frame, index, context);
    ViewSource source;
    source.image_path = ResolveImagePath(dir, file_path);
    source.name = ViewName(file_path);
    std::error_code error;
    const bool exists = fs::exists(source.image_path, error);
    if (error) {  // a symlink loop, a folder without permission: not a missing image
      context.FailFrame(index, "image " + source.image_path + ": " + error.message());
    }
    if (layout == Layout::kNgp && !exists) {
      std::fprintf(stderr, "warning: %s: frame %zu: image %s not found, skipping it\n",
                   json_path.c_str(), index, source.image_path.c_str());
      ++skipped;
      continue;
    }
    IntrinsicFields fields = shared;
    fields.ReadFrom(frame, "frame " + std::to_string(index) + ": ", context);
    source.camera = ResolveIntrinsics(fields, source.image_path, index, context, camera);
    manifest.views.push_back(std::move(source));
  }
  if (manifest.views.empty()) {
    context.Fail(
        "no frames for split '" + split + "'" +
        (skipped ? " (" + std::to_string(skipped) + " skipped because their images are missing)"
                 : ""));
  }
  if (layout == Layout::kNgp) SetNearFarFromCameras(poses, &manifest);
  return manifest;
}

// Loads one view; `had_alpha` reports whether compositing changed the background.
View LoadView(const ViewSource& source, int downscale, bool* had_alpha) {
  const ImageSize camera_size{source.camera.width, source.camera.height};
  Image image = LoadImage(source.image_path, &camera_size);
  *had_alpha = image.channels == 2 || image.channels == 4;
  View view;
  view.name = source.name;
  // Composite before averaging: box-filtering straight alpha would darken edges.
  view.rgb = DownscaleArea(CompositeOnWhite(image), downscale);
  view.camera = ScaledCamera(source.camera, downscale);
  if (view.rgb.width == 0 || view.rgb.height == 0) {
    throw std::runtime_error(source.image_path + ": downscale " + std::to_string(downscale) +
                             " leaves no pixels of a " + std::to_string(image.width) + "x" +
                             std::to_string(image.height) + " image");
  }
  return view;
}

}  // namespace

int64_t LoadedPixels(const std::vector<ViewSource>& views, int image_downscale) {
  int64_t pixels = 0;
  for (const ViewSource& view : views) {
    pixels += int64_t{view.camera.width / image_downscale} * (view.camera.height / image_downscale);
  }
  return pixels;
}

namespace {

std::vector<View> LoadViewsImpl(const std::vector<ViewSource>& sources, int downscale,
                                bool* any_alpha) {
  if (downscale < 1)
    throw std::runtime_error("downscale must be >= 1, got " + std::to_string(downscale));
  const int64_t pixels = LoadedPixels(sources, downscale);
  if (pixels > kMaxDatasetPixels) {
    throw std::runtime_error(std::to_string(sources.size()) + " views of " +
                             std::to_string(sources.front().camera.width) + "x" +
                             std::to_string(sources.front().camera.height) +
                             " (first view; downscale " + std::to_string(downscale) + ") hold " +
                             std::to_string(pixels) + " pixels; a dataset may hold at most " +
                             std::to_string(kMaxDatasetPixels) +
                             " (12 GiB as float RGB): use a larger --downscale");
  }
  // Each distinct file is decoded once: views that name the same file (the same camera size)
  // copy the first one's pixels.
  std::vector<int> first(sources.size());
  {
    std::map<std::string, int> seen;
    for (size_t i = 0; i < sources.size(); ++i) {
      std::error_code ec;
      const fs::path canonical = fs::weakly_canonical(sources[i].image_path, ec);
      const std::string key = (ec ? fs::path(sources[i].image_path) : canonical).string();
      first[i] = seen.emplace(key, int(i)).first->second;
    }
  }
  const int count = static_cast<int>(sources.size());
  std::vector<View> views(sources.size());
  std::vector<std::string> errors(sources.size());
  std::vector<char> alpha(sources.size(), 0);
#pragma omp parallel for schedule(dynamic)
  for (int i = 0; i < count; ++i) {
    if (first[i] != i) continue;
    // Exceptions must not leave an OpenMP region; keep each view's error for later.
    try {
      bool had_alpha = false;
      views[i] = LoadView(sources[i], downscale, &had_alpha);
      alpha[i] = had_alpha;
    } catch (const std::exception& error) {
      errors[i] = error.what();
    }
  }
  for (const std::string& error : errors) {
    if (!error.empty()) throw std::runtime_error(error);
  }
  for (int i = 0; i < count; ++i) {
    const int f = first[i];
    if (f == i) continue;
    const ViewSource& s = sources[i];
    if (s.camera.width != sources[f].camera.width || s.camera.height != sources[f].camera.height) {
      throw std::runtime_error(
          s.image_path + ": its camera says " + std::to_string(s.camera.width) + "x" +
          std::to_string(s.camera.height) + ", another frame's " +
          std::to_string(sources[f].camera.width) + "x" + std::to_string(sources[f].camera.height));
    }
    views[i].name = s.name;
    views[i].rgb = views[f].rgb;
    views[i].camera = ScaledCamera(s.camera, downscale);
    alpha[i] = alpha[f];
  }
  *any_alpha = std::find(alpha.begin(), alpha.end(), 1) != alpha.end();
  return views;
}

}  // namespace

void NgpAabb(double aabb_scale, double scale, const double offset[3], double aabb[2][3]) {
  const double half_extent = 0.5 * aabb_scale / scale;
  for (int a = 0; a < 3; ++a) {
    const double centre = (0.5 - offset[a]) / scale;
    aabb[0][a] = centre - half_extent;
    aabb[1][a] = centre + half_extent;
  }
}

// Real captures have no agreed near/far, so derive them from the geometry: near is the
// smallest camera-to-box distance (the box holds everything modelled), far the largest
// distance from a camera to a box corner (no ray leaves the box later).
void NearFarFromCameras(const std::vector<Camera>& cameras, const double box[2][3],
                        double* near_out, double* far_out) {
  double diagonal_sq = 0;
  for (int a = 0; a < 3; ++a) diagonal_sq += (box[1][a] - box[0][a]) * (box[1][a] - box[0][a]);
  double near = INFINITY, far = 0;
  for (const Camera& camera : cameras) {
    double to_box_sq = 0, to_corner_sq = 0;
    for (int a = 0; a < 3; ++a) {
      const double p = camera.c2w[a][3];
      const double outside = std::max({box[0][a] - p, 0.0, p - box[1][a]});
      const double corner = std::max(std::abs(p - box[0][a]), std::abs(p - box[1][a]));
      to_box_sq += outside * outside;
      to_corner_sq += corner * corner;
    }
    near = std::min(near, std::sqrt(to_box_sq));
    far = std::max(far, std::sqrt(to_corner_sq));
  }
  *near_out = std::max(near, kMinNearFraction * std::sqrt(diagonal_sq));
  *far_out = std::max(far, *near_out * 1.01);
}

std::vector<Camera> ReadTransformsCameras(const std::string& json_path, int default_width,
                                          int default_height) {
  JsonContext context(json_path);
  const json root = ReadJson(json_path);
  IntrinsicFields shared;
  const json& frames = TransformFrames(root, &context, &shared);
  std::vector<Camera> cameras;
  for (size_t i = 0; i < frames.size(); ++i) {
    Camera camera;
    ReadTransform(frames[i], i, context, &camera);
    IntrinsicFields fields = shared;
    fields.ReadFrom(frames[i], "frame " + std::to_string(i) + ": ", context);
    // No image to take the size from: the caller's size stands in for a missing one.
    if (!fields.w) fields.w = default_width;
    if (!fields.h) fields.h = default_height;
    cameras.push_back(ResolveIntrinsics(fields, "", i, context, camera));
  }
  return cameras;
}

DatasetManifest ReadDatasetManifest(const std::string& dir, const std::string& split,
                                    int downscale) {
  if (split != "train" && split != "val" && split != "test") {
    throw std::runtime_error("unknown split '" + split + "' (expected train, val or test)");
  }
  std::error_code error;
  if (!fs::exists(dir, error)) throw std::runtime_error(dir + ": no such directory");
  if (!fs::is_directory(dir, error)) throw std::runtime_error(dir + ": not a directory");
  const fs::path root(dir);
  const fs::path blender = root / ("transforms_" + split + ".json");
  if (fs::exists(blender, error))
    return ParseTransforms(root, blender.string(), Layout::kBlender, split);
  const fs::path ngp = root / "transforms.json";
  if (fs::exists(ngp, error)) {
    DatasetManifest manifest = ParseTransforms(root, ngp.string(), Layout::kNgp, split);
    manifest.estimated_poses = true;
    return manifest;
  }
  if (fs::exists(root / "poses_bounds.npy", error)) {
    int prescaled = 1;
    DatasetManifest manifest = ReadLlffManifest(dir, split, downscale, &prescaled);
    manifest.prescaled = prescaled;
    manifest.estimated_poses = true;
    return manifest;
  }
  // Photos without poses: `ecrf prepare` makes a dataset of them (docs/photos-to-dataset.md).
  bool photos = false;
  for (const auto& entry : fs::directory_iterator(root, error)) {
    std::string ext = entry.path().extension().string();
    for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    photos = photos || ext == ".jpg" || ext == ".jpeg" || ext == ".png";
  }
  throw std::runtime_error(
      dir + ": neither transforms_" + split + ".json nor transforms.json found " +
      "(Blender, Instant-NGP), nor poses_bounds.npy (LLFF)" +
      (photos ? std::string("; for photos without camera poses: ecrf prepare " + dir +
                            " -o DATASET_DIR, then --data DATASET_DIR")
              : std::string()));
}

std::vector<View> LoadViews(const std::vector<ViewSource>& sources, int downscale) {
  bool any_alpha = false;
  return LoadViewsImpl(sources, downscale, &any_alpha);
}

Dataset LoadDataset(const std::string& dir, const std::string& split, int downscale) {
  if (downscale < 1)
    throw std::runtime_error(dir + ": downscale must be >= 1, got " + std::to_string(downscale));
  DatasetManifest manifest = ReadDatasetManifest(dir, split, downscale);
  Dataset dataset;
  bool any_alpha = false;
  dataset.views = LoadViewsImpl(manifest.views, ImageDownscale(manifest, downscale), &any_alpha);
  std::copy(&manifest.scene_aabb[0][0], &manifest.scene_aabb[0][0] + 6, &dataset.scene_aabb[0][0]);
  dataset.near = manifest.near;
  dataset.far = manifest.far;
  dataset.estimated_poses = manifest.estimated_poses;
  // Transparent pixels were composited on white, so those backgrounds are white now.
  dataset.white_background = manifest.white_background || any_alpha;
  return dataset;
}

Dataset DownscaleViews(Dataset dataset, int factor) {
  if (factor < 1)
    throw std::invalid_argument("downscale must be >= 1, got " + std::to_string(factor));
  if (factor == 1) return dataset;
  for (View& view : dataset.views) {
    if (view.rgb.width < factor || view.rgb.height < factor) {
      throw std::invalid_argument("downscale " + std::to_string(factor) + " leaves no pixel of a " +
                                  std::to_string(view.rgb.width) + "x" +
                                  std::to_string(view.rgb.height) + " view");
    }
    view.rgb = DownscaleArea(view.rgb, factor);
    view.camera = ScaledCamera(view.camera, factor);
  }
  return dataset;
}

}  // namespace ecrf::trainer
