#include "tools/prepare/prepare_dataset.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include "tools/cli.h"
#include "tools/prepare/colmap_model.h"
#include "tools/prepare/colmap_progress.h"
#include "tools/run_program.h"
#include "trainer/data/image_io.h"

namespace ecrf {
namespace tools {
namespace {

namespace fs = std::filesystem;

std::string Lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool IsImageName(const fs::path& path) {
  const std::string ext = Lower(path.extension().string());
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

// The output may not exist, or be an empty folder; its parent must exist.
void CheckOutput(const std::string& out_dir) {
  std::error_code ec;
  const fs::path out(out_dir);
  if (fs::exists(out, ec)) {
    if (!fs::is_directory(out, ec) || !fs::is_empty(out, ec)) {
      throw std::runtime_error(out_dir +
                               " exists and is not an empty folder: choose another -o (ecrf "
                               "prepare never overwrites a dataset)");
    }
  }
  const fs::path parent = fs::absolute(out, ec).parent_path();
  if (!fs::is_directory(parent, ec)) {
    throw std::runtime_error(out_dir + ": its folder " + parent.string() + " does not exist");
  }
}

// Removes the temporary folder unless the dataset was moved into place.
class TemporaryDir {
 public:
  explicit TemporaryDir(fs::path path) : path_(std::move(path)) {
    std::error_code ec;
    fs::create_directories(path_ / "images", ec);
    if (ec) throw std::runtime_error(path_.string() + ": cannot create (" + ec.message() + ")");
  }
  ~TemporaryDir() {
    if (path_.empty()) return;
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  void MoveTo(const fs::path& out) {
    std::error_code ec;
    if (fs::exists(out, ec)) fs::remove(out, ec);  // the empty folder CheckOutput allowed
    fs::rename(path_, out, ec);
    if (ec) {
      throw std::runtime_error("cannot rename " + path_.string() + " to " + out.string() + " (" +
                               ec.message() + ")");
    }
    path_.clear();
  }

 private:
  fs::path path_;
};

std::string Executable(const std::string& name, const char* package, const char* what) {
  const std::string path = FindExecutable(name);
  if (path.empty()) {
    throw std::runtime_error(std::string(what) + " needs " + name + ", which is not installed (" +
                             "on Debian: apt-get install " + package + ")");
  }
  return path;
}

// Runs one step; a COLMAP phase of `frames` frames (frames > 0) shows its progress as it goes.
void Run(const std::vector<std::string>& argv, const std::string& step, int frames = 0) {
  std::fprintf(stderr, "prepare: %s\n", step.c_str());
  ColmapProgress progress(step, frames);
  const ProgramResult result =
      frames > 0 ? RunProgram(argv, [&progress](const std::string& line) { progress(line); })
                 : RunProgram(argv);
  progress.Finish();
  if (!result.Succeeded()) {
    throw std::runtime_error(step + " failed (" + result.Status() + "): " + ShellCommandLine(argv) +
                             "\n" + TailLines(result.error_tail, 12));
  }
}

// The PNG and JPEG files of a folder, in name order.
std::vector<fs::path> ImagesIn(const fs::path& dir) {
  std::vector<fs::path> images;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    if (e.is_regular_file(ec) && IsImageName(e.path())) images.push_back(e.path());
  }
  if (ec) throw std::runtime_error(dir.string() + ": cannot list (" + ec.message() + ")");
  std::sort(images.begin(), images.end());
  return images;
}

// The photos of a folder, copied (hard links where the file system allows). A JPEG stored
// sideways (its EXIF orientation) is written upright as a PNG of the same name: COLMAP reads the
// stored pixels, and the trainer turns JPEGs upright, so both must see the upright image.
void CopyPhotos(const fs::path& input, const fs::path& images) {
  std::error_code ec;
  for (const fs::path& p : ImagesIn(input)) {
    if (trainer::ReadImageSize(p.string()).orientation != 1) {
      fs::path to = images / p.filename();
      to.replace_extension(".png");
      if (fs::exists(to, ec) || fs::exists(input / to.filename(), ec)) {
        throw std::runtime_error(p.string() + ": stored sideways (EXIF orientation), and " +
                                 to.filename().string() +
                                 " for its upright copy is taken; rename one of them");
      }
      trainer::SavePng(to.string(), trainer::LoadImage(p.string()));
      continue;
    }
    const fs::path to = images / p.filename();
    fs::create_hard_link(p, to, ec);
    if (ec) {
      ec.clear();
      fs::copy_file(p, to, ec);
      if (ec) throw std::runtime_error(p.string() + ": cannot copy (" + ec.message() + ")");
    }
  }
}

void ExtractFrames(const std::string& ffmpeg, const PrepareOptions& o, const fs::path& images) {
  std::string filter = "fps=" + std::to_string(o.fps);
  if (o.max_size > 0) {
    const std::string s = std::to_string(o.max_size);
    // The longer side becomes max_size (never enlarged), the other keeps the aspect, even.
    filter += ",scale='if(gte(iw,ih),min(" + s + ",iw),-2)':'if(gte(iw,ih),-2,min(" + s + ",ih))'";
  }
  Run({ffmpeg, "-nostdin", "-v", "error", "-i", FfmpegFileName(o.input), "-vf", filter, "-frames:v",
       std::to_string(o.max_frames), "-q:v", "2",
       FfmpegFileName((images / "frame_%05d.jpg").string())},
      "extracting frames from " + o.input + " (ffmpeg)");
}

// COLMAP's SIFT extraction and matching as the plan says, into the database db.
void ExtractAndMatch(const std::string& colmap, const PrepareOptions& o, const MatchPlan& plan,
                     bool video, const fs::path& images, const fs::path& db, int threads,
                     int frames) {
  std::vector<std::string> extract = {colmap,
                                      "feature_extractor",
                                      "--database_path",
                                      db.string(),
                                      "--image_path",
                                      images.string(),
                                      "--ImageReader.single_camera",
                                      "1",
                                      "--ImageReader.camera_model",
                                      o.camera_model,
                                      "--SiftExtraction.use_gpu",
                                      "0",
                                      "--SiftExtraction.num_threads",
                                      std::to_string(threads),
                                      "--SiftExtraction.max_num_features",
                                      std::to_string(plan.max_features)};
  if (o.max_size > 0 && !video) {
    // Photos keep their size (the trainer's --downscale shrinks them); SIFT reads them shrunk to
    // --max-size, which is most of its time on large photos (frames of a video are scaled by
    // ffmpeg already).
    extract.insert(extract.end(), {"--SiftExtraction.max_image_size", std::to_string(o.max_size)});
  }
  Run(extract, "COLMAP feature extraction of " + std::to_string(frames) + " frames", frames);
  std::vector<std::string> match = {colmap,
                                    plan.matcher + "_matcher",
                                    "--database_path",
                                    db.string(),
                                    "--SiftMatching.use_gpu",
                                    "0",
                                    "--SiftMatching.num_threads",
                                    std::to_string(threads)};
  if (plan.matcher == "sequential") {
    match.insert(match.end(), {"--SequentialMatching.overlap", std::to_string(kSequentialOverlap),
                               "--SequentialMatching.quadratic_overlap", "1"});
  }
  Run(match,
      "COLMAP " + plan.matcher + " matching (at most " + std::to_string(plan.pairs) +
          " pairs of frames)",
      frames);
}

}  // namespace

PrepareResult PrepareDataset(const PrepareOptions& o) {
  trainer::ChoiceFromName<ColmapCameraModel>(o.camera_model, "--camera-model " + o.camera_model);
  trainer::ChoiceFromName<ColmapMatcher>(o.matcher, "--matcher " + o.matcher);
  if (!(o.fps > 0) || o.max_frames < 3 || o.max_features < 0 || o.max_size < 0 ||
      o.aabb_scale < 1 || !(o.min_registered >= 0 && o.min_registered <= 1)) {
    throw std::invalid_argument(
        "need --fps > 0, --max-frames >= 3, --max-size >= 0, --aabb-scale >= 1 and "
        "--min-registered in [0, 1]");
  }
  std::error_code ec;
  const fs::path input(o.input);
  if (!fs::exists(input, ec)) throw std::runtime_error(o.input + ": no such file or folder");
  const bool video = !fs::is_directory(input, ec);
  CheckOutput(o.out_dir);
  const std::string colmap = Executable(o.colmap, "colmap", "ecrf prepare");
  const std::string ffmpeg =
      video ? Executable(o.ffmpeg, "ffmpeg", "ecrf prepare with a video") : std::string();

  const fs::path out = fs::absolute(fs::path(o.out_dir), ec);
  TemporaryDir tmp(out.parent_path() /
                   (out.filename().string() + ".partial." + std::to_string(::getpid())));
  const fs::path images = tmp.path() / "images";
  PrepareResult result;
  if (video) {
    ExtractFrames(ffmpeg, o, images);
  } else {
    CopyPhotos(input, images);
  }
  std::vector<std::string> all;  // the frames COLMAP gets, by name
  for (const fs::path& p : ImagesIn(images)) all.push_back(p.filename().string());
  result.frames = int(all.size());
  if (result.frames < 3) {
    throw std::runtime_error(o.input + ": " + std::to_string(result.frames) +
                             (video ? " frames extracted" : " PNG or JPEG images") +
                             "; structure from motion needs at least 3");
  }

  const MatchPlan plan = PlanMatching(video, result.frames, o.matcher, o.max_features);
  result.plan = plan;
  std::fprintf(stderr,
               "prepare: %d %s: COLMAP %s matching of at most %lld pairs, %d SIFT features a "
               "frame%s; about %.0f min of matching for real photos on 2 cores\n",
               result.frames, video ? "frames" : "photos", plan.matcher.c_str(), plan.pairs,
               plan.max_features,
               plan.features_auto ? " (automatic; --max-features N sets it)" : "",
               plan.predicted_seconds / 60.0);
  const int threads = o.threads > 0 ? o.threads : AllCores();
  const fs::path db = tmp.path() / "colmap" / "database.db";
  const fs::path sparse = tmp.path() / "colmap" / "sparse";
  fs::create_directories(sparse, ec);
  ExtractAndMatch(colmap, o, plan, video, images, db, threads, result.frames);
  Run({colmap, "mapper", "--database_path", db.string(), "--image_path", images.string(),
       "--output_path", sparse.string(), "--Mapper.num_threads", std::to_string(threads)},
      "COLMAP mapping", result.frames);

  // COLMAP writes one folder per disconnected reconstruction: keep the one with most images.
  ColmapModel best;
  for (const fs::directory_entry& e : fs::directory_iterator(sparse, ec)) {
    if (!e.is_directory(ec)) continue;
    const fs::path text = tmp.path() / "colmap" / "text" / e.path().filename();
    fs::create_directories(text, ec);
    Run({colmap, "model_converter", "--input_path", e.path().string(), "--output_path",
         text.string(), "--output_type", "TXT"},
        "COLMAP model conversion of reconstruction " + e.path().filename().string());
    ColmapModel model = ReadColmapTextModel(text.string());
    ++result.models;
    if (model.images.size() > best.images.size()) best = std::move(model);
  }
  result.registered = int(best.images.size());
  std::vector<std::string> posed;
  for (const ColmapImage& im : best.images) posed.push_back(im.name);
  std::sort(posed.begin(), posed.end());
  std::set_difference(all.begin(), all.end(), posed.begin(), posed.end(),
                      std::back_inserter(result.unregistered));
  if (result.registered < 3 || result.registered < o.min_registered * result.frames) {
    std::string names;
    for (size_t i = 0; i < result.unregistered.size() && i < 8; ++i)
      names += (i ? ", " : "") + result.unregistered[i];
    if (result.unregistered.size() > 8) names += ", ...";
    throw std::runtime_error(
        "COLMAP posed " + std::to_string(result.registered) + " of " +
        std::to_string(result.frames) + " frames (" + std::to_string(result.models) +
        " reconstructions; --min-registered " + std::to_string(o.min_registered) +
        "); without a pose: " + names +
        ". Photos need overlap (each scene point in several photos), texture and sharpness; "
        "more frames (--fps) or --matcher exhaustive may help");
  }
  NormalizeColmapPoses(&best.images, 4.0);
  {
    std::ofstream json(tmp.path() / "transforms.json");
    json << TransformsJson(best, best.images, o.aabb_scale, "images");
    if (!json) throw std::runtime_error(tmp.path().string() + "/transforms.json: cannot write");
  }
  tmp.MoveTo(out);
  return result;
}

}  // namespace tools
}  // namespace ecrf
