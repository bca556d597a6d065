// `ecrf render --video OUT.mp4`: the rendered PNG frames encoded by Debian's ffmpeg as H.264
// (libx264, yuv420p, even width and height, the index at the front for streaming). ffmpeg runs
// as a separate program, not a library: ecrf keeps no codec dependency, and a machine without
// ffmpeg still gets the frames and the command that makes the video.
#ifndef ECRF_TOOLS_VIDEO_WRITER_H_
#define ECRF_TOOLS_VIDEO_WRITER_H_

#include <string>
#include <vector>

namespace ecrf {
namespace tools {

// What to encode: frames DIR/PATTERN.png for k = 0 .. count - 1 (PATTERN is printf-like,
// "orbit_%03d"), all width x height.
struct VideoJob {
  std::string frames_dir;
  std::string frame_pattern;
  int count = 0;
  int width = 0, height = 0;
  int fps = 30;
  std::string output;  // the .mp4 to write
};

// Before rendering (the frames may take minutes): the output ends in .mp4, is not a directory,
// and a file can be created in its directory (proved with a probe file, removed again). Throws
// std::runtime_error naming the path and the reason.
void CheckVideoOutput(const std::string& output);

// A new empty directory next to the video for frames that are not kept
// (DIR/.NAME.mp4.frames-XXXXXX): on the video's file system, which has room for the video.
std::string MakeFramesDirectory(const std::string& output);

// ffmpeg's arguments after the program name, writing to `output` (the video, or the temporary
// file EncodeVideo renames). batch: no banner or progress, only errors, no questions (-nostdin,
// -y) and the container named (the temporary file has no .mp4 extension).
std::vector<std::string> FfmpegArguments(const VideoJob& job, const std::string& output,
                                         bool batch);

// The command that makes the video from the frames, to print when ffmpeg is missing:
// `ffmpeg` (the name as given to --ffmpeg) and the arguments, quoted for a POSIX shell.
std::string FfmpegCommandLine(const std::string& ffmpeg, const VideoJob& job);

// Runs ffmpeg (an executable's path, see FindExecutable) on the job into a temporary file next
// to job.output and renames it onto job.output once ffmpeg succeeded, so that a failed or
// interrupted encode never leaves a half-written video under the real name. Throws
// std::runtime_error with ffmpeg's exit status and the end of its error output.
void EncodeVideo(const std::string& ffmpeg, const VideoJob& job);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_VIDEO_WRITER_H_
