#include "tools/video_writer.h"

#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "tools/cli_args.h"
#include "tools/run_program.h"

namespace ecrf {
namespace tools {
namespace {

// The directory a file goes into and its name in it.
void SplitPath(const std::string& path, std::string* dir, std::string* name) {
  const size_t slash = path.find_last_of('/');
  *dir = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
  *name = slash == std::string::npos ? path : path.substr(slash + 1);
}

bool EndsWithMp4(const std::string& path) {
  if (path.size() < 4) return false;
  std::string end = path.substr(path.size() - 4);
  for (char& c : end) c = char(std::tolower(static_cast<unsigned char>(c)));
  return end == ".mp4";
}

// The temporary name a video is encoded under, beside it (rename() is atomic within a directory).
std::string TemporaryVideoName(const std::string& output) {
  return output + ".tmp." + std::to_string(::getpid());
}

// The frames as ffmpeg's image-sequence pattern; a '%' of the directory is a literal "%%".
std::string SequencePattern(const VideoJob& job) {
  std::string dir;
  for (char c : job.frames_dir) dir += c == '%' ? std::string("%%") : std::string(1, c);
  return FfmpegFileName(dir + "/" + job.frame_pattern + ".png");
}

}  // namespace

void CheckVideoOutput(const std::string& output) {
  if (!EndsWithMp4(output)) {
    throw std::runtime_error("--video " + output +
                             ": the name must end in .mp4 (the video is H.264 in MP4)");
  }
  if (IsDirectory(output)) throw std::runtime_error("--video " + output + ": is a directory");
  std::string dir, name;
  SplitPath(output, &dir, &name);
  if (!IsDirectory(dir)) {
    throw std::runtime_error("--video " + output + ": cannot write the video: directory " + dir +
                             " does not exist");
  }
  const std::string probe = TemporaryVideoName(output);
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644);
  if (fd < 0) {
    throw std::runtime_error("--video " + output + ": cannot create a file in " + dir + ": " +
                             std::strerror(errno));
  }
  ::close(fd);
  ::unlink(probe.c_str());
}

std::string MakeFramesDirectory(const std::string& output) {
  std::string dir, name;
  SplitPath(output, &dir, &name);
  std::string pattern = dir + "/." + name + ".frames-XXXXXX";
  if (!mkdtemp(pattern.data())) {
    throw std::runtime_error("--video " + output +
                             ": cannot create a directory for the frames in " + dir + ": " +
                             std::strerror(errno));
  }
  return pattern;
}

std::vector<std::string> FfmpegArguments(const VideoJob& job, const std::string& output,
                                         bool batch) {
  std::vector<std::string> args;
  if (batch) args = {"-hide_banner", "-nostdin", "-loglevel", "error", "-y"};
  const std::vector<std::string> input = {
      "-framerate", std::to_string(job.fps), "-start_number", "0", "-i", SequencePattern(job)};
  args.insert(args.end(), input.begin(), input.end());
  // yuv420p (what every player decodes) stores colour at half resolution, so H.264 needs even
  // sizes: an odd size loses its last column or row rather than being resampled.
  if (job.width % 2 || job.height % 2) {
    args.insert(args.end(), {"-vf", "crop=trunc(iw/2)*2:trunc(ih/2)*2"});
  }
  // The count, because the image2 reader takes every number in sequence: frames left in -o DIR by
  // a longer earlier run would otherwise end up in the video.
  args.insert(args.end(), {"-frames:v", std::to_string(job.count), "-c:v", "libx264", "-pix_fmt",
                           "yuv420p", "-movflags", "+faststart"});
  if (batch) args.insert(args.end(), {"-f", "mp4"});
  args.push_back(FfmpegFileName(output));
  return args;
}

std::string FfmpegCommandLine(const std::string& ffmpeg, const VideoJob& job) {
  std::vector<std::string> argv = {ffmpeg};
  const std::vector<std::string> args = FfmpegArguments(job, job.output, false);
  argv.insert(argv.end(), args.begin(), args.end());
  return ShellCommandLine(argv);
}

void EncodeVideo(const std::string& ffmpeg, const VideoJob& job) {
  const std::string temporary = TemporaryVideoName(job.output);
  std::vector<std::string> argv = {ffmpeg};
  const std::vector<std::string> args = FfmpegArguments(job, temporary, true);
  argv.insert(argv.end(), args.begin(), args.end());
  ProgramResult result;
  try {
    result = RunProgram(argv);
  } catch (const std::exception&) {
    std::remove(temporary.c_str());
    throw;
  }
  if (!result.Succeeded()) {
    std::remove(temporary.c_str());
    const std::string tail = TailLines(result.error_tail, 10);
    throw std::runtime_error("--video " + job.output + ": " + ffmpeg + " failed (" +
                             result.Status() + ") encoding " + std::to_string(job.count) +
                             " frames from " + job.frames_dir +
                             (tail.empty() ? " and wrote no message" : "; it said:\n" + tail));
  }
  if (std::rename(temporary.c_str(), job.output.c_str()) != 0) {
    const int error = errno;
    std::remove(temporary.c_str());
    throw std::runtime_error("--video " + job.output + ": cannot rename " + temporary +
                             " into place: " + std::strerror(error));
  }
}

}  // namespace tools
}  // namespace ecrf
