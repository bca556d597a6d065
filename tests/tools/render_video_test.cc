// `ecrf render` with camera paths and --video, in-process on the small conformance scene: a path
// saved with --save-path renders the same frames through --path; --video makes an H.264 MP4
// with one frame per camera (checked with ffprobe; skipped where ffmpeg is not installed);
// without ffmpeg the frames stay and the command that makes the video is printed (and works);
// a failing ffmpeg or an unwritable video is one clear error that leaves no file behind.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "tests/common/invoke.h"
#include "tests/common/scoped_temp_dir.h"
#include "tools/commands.h"
#include "tools/run_program.h"

namespace ecrf {
namespace tools {
namespace {

namespace fs = std::filesystem;
using testing_cli::Invoke;

const std::string kScene = std::string(ECRF_SOURCE_DIR) + "/tests/conformance/scene_builtin.ecrf";

struct Output {
  int rc = 0;
  std::string out, err;
};

// `ecrf ARGS...` through the whole command line, so a thrown error is "ecrf render: error: ...".
Output Ecrf(std::vector<std::string> args) {
  args.insert(args.begin(), "ecrf");
  Output r;
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  r.rc = Invoke(RunEcrf, args);
  r.out = ::testing::internal::GetCapturedStdout();
  r.err = ::testing::internal::GetCapturedStderr();
  return r;
}

class RenderVideo : public ::testing::Test {
 protected:
  const testing_util::ScopedTempDir tmp_{"ecrf_render_video_test"};
  const std::string dir_ = tmp_.path();
};

std::vector<std::string> Listing(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename());
  std::sort(names.begin(), names.end());
  return names;
}

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

bool HaveFfmpeg() {
  return !FindExecutable("ffmpeg").empty() && !FindExecutable("ffprobe").empty();
}

// ffprobe's figures for the video stream: codec_name, width, height, pix_fmt, nb_read_frames
// (frames counted by decoding the whole stream, not read from the header).
std::map<std::string, std::string> Probe(const std::string& video) {
  const std::string command =
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
      "stream=codec_name,width,height,pix_fmt,nb_read_frames -of default=noprint_wrappers=1 '" +
      video + "'";
  std::map<std::string, std::string> fields;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return fields;
  char line[256];
  while (std::fgets(line, sizeof(line), pipe)) {
    std::string text(line);
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
    const size_t eq = text.find('=');
    if (eq != std::string::npos) fields[text.substr(0, eq)] = text.substr(eq + 1);
  }
  pclose(pipe);
  return fields;
}

// MP4's index (moov) before the media data (mdat): -movflags +faststart, so a browser can start
// playing before the whole file arrived.
void ExpectIndexFirst(const std::string& video) {
  const std::string bytes = ReadBytes(video);
  const size_t moov = bytes.find("moov"), mdat = bytes.find("mdat");
  ASSERT_NE(moov, std::string::npos);
  ASSERT_NE(mdat, std::string::npos);
  EXPECT_LT(moov, mdat);
}

TEST_F(RenderVideo, SavedPathRendersTheSameFramesAsTheSpiral) {
  const std::string path = dir_ + "/spiral.json";
  const Output save = Ecrf({"render", kScene, "--spiral", "3", "-W", "16", "-H", "12",
                            "--spiral-cycles", "1", "--save-path", path});
  ASSERT_EQ(save.rc, 0) << save.err;
  EXPECT_NE(save.out.find("wrote 3 cameras to " + path), std::string::npos) << save.out;
  EXPECT_EQ(save.out.find("rendered"), std::string::npos) << save.out;  // alone: nothing rendered
  const Output spiral = Ecrf({"render", kScene, "--spiral", "3", "-W", "16", "-H", "12",
                              "--spiral-cycles", "1", "--threads", "1", "-o", dir_ + "/spiral"});
  ASSERT_EQ(spiral.rc, 0) << spiral.err;
  // -W / -H differ on purpose: the file's sizes win over the defaults.
  const Output replay = Ecrf(
      {"render", kScene, "--path", path, "-W", "99", "--threads", "1", "-o", dir_ + "/replay"});
  ASSERT_EQ(replay.rc, 0) << replay.err;
  EXPECT_EQ(Listing(dir_ + "/spiral"),
            (std::vector<std::string>{"spiral_000.png", "spiral_001.png", "spiral_002.png"}));
  EXPECT_EQ(Listing(dir_ + "/replay"),
            (std::vector<std::string>{"path_000.png", "path_001.png", "path_002.png"}));
  for (int k = 0; k < 3; ++k) {
    const std::string a = ReadBytes(dir_ + "/spiral/spiral_00" + std::to_string(k) + ".png");
    EXPECT_FALSE(a.empty());
    EXPECT_EQ(a, ReadBytes(dir_ + "/replay/path_00" + std::to_string(k) + ".png")) << k;
  }
}

TEST_F(RenderVideo, VideoHasOneFramePerCamera) {
  if (!HaveFfmpeg()) GTEST_SKIP() << "ffmpeg / ffprobe not installed (apt-get install ffmpeg)";
  const std::string video = dir_ + "/orbit.mp4";
  const Output r =
      Ecrf({"render", kScene, "--orbit", "6", "-W", "32", "-H", "32", "--video", video});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("wrote " + video + ": 6 frames of 32x32 at 30 fps"), std::string::npos)
      << r.out;
  // No PNGs kept without -o, no temporary file or directory left.
  EXPECT_EQ(Listing(dir_), std::vector<std::string>{"orbit.mp4"});
  const auto p = Probe(video);
  EXPECT_EQ(p.count("nb_read_frames") ? p.at("nb_read_frames") : "", "6");
  EXPECT_EQ(p.count("codec_name") ? p.at("codec_name") : "", "h264");
  EXPECT_EQ(p.count("pix_fmt") ? p.at("pix_fmt") : "", "yuv420p");
  EXPECT_EQ(p.count("width") ? p.at("width") : "", "32");
  EXPECT_EQ(p.count("height") ? p.at("height") : "", "32");
  ExpectIndexFirst(video);
}

TEST_F(RenderVideo, OddSizesAreCroppedAndFramesKeptWithOut) {
  if (!HaveFfmpeg()) GTEST_SKIP() << "ffmpeg / ffprobe not installed (apt-get install ffmpeg)";
  // A longer earlier run left spiral_005 and spiral_006 in the directory: not in the video.
  const Output before =
      Ecrf({"render", kScene, "--spiral", "7", "-W", "33", "-H", "19", "-o", dir_ + "/frames"});
  ASSERT_EQ(before.rc, 0) << before.err;
  const std::string video = dir_ + "/spiral.mp4";
  const Output r = Ecrf({"render", kScene, "--spiral", "5", "-W", "33", "-H", "19", "--fps", "12",
                         "--video", video, "-o", dir_ + "/frames"});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("5 frames of 32x18 at 12 fps"), std::string::npos) << r.out;
  EXPECT_EQ(Listing(dir_ + "/frames"),
            (std::vector<std::string>{"spiral_000.png", "spiral_001.png", "spiral_002.png",
                                      "spiral_003.png", "spiral_004.png", "spiral_005.png",
                                      "spiral_006.png"}));
  EXPECT_EQ(Listing(dir_), (std::vector<std::string>{"frames", "spiral.mp4"}));
  const auto p = Probe(video);
  EXPECT_EQ(p.count("nb_read_frames") ? p.at("nb_read_frames") : "", "5");
  EXPECT_EQ(p.count("width") ? p.at("width") : "", "32");
  EXPECT_EQ(p.count("height") ? p.at("height") : "", "18");
}

TEST_F(RenderVideo, WithoutFfmpegTheFramesAndTheCommandAppear) {
  const std::string video = dir_ + "/orbit.mp4";
  const Output r = Ecrf({"render", kScene, "--orbit", "4", "-W", "16", "-H", "16", "--video", video,
                         "--ffmpeg", dir_ + "/no/ffmpeg"});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_EQ(Listing(dir_ + "/orbit_frames"),
            (std::vector<std::string>{"orbit_000.png", "orbit_001.png", "orbit_002.png",
                                      "orbit_003.png"}));
  EXPECT_FALSE(fs::exists(video));
  EXPECT_NE(r.out.find(dir_ + "/no/ffmpeg not found (no such executable), so " + video +
                       " was not written; the 4 frames are in " + dir_ + "/orbit_frames"),
            std::string::npos)
      << r.out;
  const std::string command =
      dir_ + "/no/ffmpeg -framerate 30 -start_number 0 -i " + dir_ +
      "/orbit_frames/orbit_%03d.png -frames:v 4 -c:v libx264 -pix_fmt yuv420p "
      "-movflags +faststart " +
      video;
  const size_t at = r.out.find("\n  " + command + "\n");
  ASSERT_NE(at, std::string::npos) << r.out;
  // The printed command is the one that makes the video.
  if (!HaveFfmpeg()) return;
  const std::string run =
      "ffmpeg -loglevel error -nostdin" + command.substr(command.find(" -framerate"));
  ASSERT_EQ(std::system(run.c_str()), 0) << run;
  const auto p = Probe(video);
  EXPECT_EQ(p.count("nb_read_frames") ? p.at("nb_read_frames") : "", "4");
}

TEST_F(RenderVideo, AnEmptyPathMeansNoFfmpeg) {
  const char* saved = std::getenv("PATH");
  const std::string path = saved ? saved : "";
  setenv("PATH", "", 1);
  const Output r = Ecrf({"render", kScene, "--orbit", "2", "-W", "8", "-H", "8", "--video",
                         dir_ + "/o.mp4", "-o", dir_ + "/pngs"});
  setenv("PATH", path.c_str(), 1);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("ffmpeg not found (not on PATH)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("the 2 frames are in " + dir_ + "/pngs"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n  ffmpeg -framerate 30 "), std::string::npos) << r.out;
  EXPECT_EQ(Listing(dir_ + "/pngs"), (std::vector<std::string>{"orbit_000.png", "orbit_001.png"}));
}

TEST_F(RenderVideo, AFailingFfmpegIsAnErrorWithItsMessage) {
  const std::string fake = dir_ + "/fake-ffmpeg";
  std::ofstream(fake) << "#!/bin/sh\necho 'some warning' >&2\necho 'Unknown encoder libx264' >&2\n"
                         "exit 3\n";
  fs::permissions(fake, fs::perms::owner_all);
  const std::string video = dir_ + "/orbit.mp4";
  const Output r = Ecrf(
      {"render", kScene, "--orbit", "2", "-W", "8", "-H", "8", "--video", video, "--ffmpeg", fake});
  EXPECT_EQ(r.rc, 1);
  EXPECT_EQ(r.err.rfind("ecrf render: error: --video " + video + ": " + fake +
                            " failed (exit status 3) encoding 2 frames from ",
                        0),
            0u)
      << r.err;
  EXPECT_NE(r.err.find("some warning\nUnknown encoder libx264\n"), std::string::npos) << r.err;
  // No video, no temporary video; the frames stay for another try, where the message says.
  std::vector<std::string> names = Listing(dir_);
  ASSERT_EQ(names.size(), 2u) << ::testing::PrintToString(names);
  EXPECT_EQ(names[0].rfind(".orbit.mp4.frames-", 0), 0u) << names[0];
  EXPECT_EQ(names[1], "fake-ffmpeg");
  EXPECT_NE(r.err.find(dir_ + "/" + names[0]), std::string::npos) << r.err;
  EXPECT_EQ(Listing(dir_ + "/" + names[0]),
            (std::vector<std::string>{"orbit_000.png", "orbit_001.png"}));
}

TEST_F(RenderVideo, UnwritableOrMisnamedVideoFailsBeforeRendering) {
  Output r = Ecrf({"render", kScene, "--orbit", "2", "--video", dir_ + "/no/such/dir/o.mp4"});
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("--video " + dir_ +
                       "/no/such/dir/o.mp4: cannot write the video: "
                       "directory " +
                       dir_ + "/no/such/dir does not exist"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;  // nothing rendered
  r = Ecrf({"render", kScene, "--orbit", "2", "--video", dir_ + "/o.avi"});
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("the name must end in .mp4"), std::string::npos) << r.err;
  r = Ecrf({"render", kScene, "--orbit", "2", "--video", dir_});
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("must end in .mp4"), std::string::npos) << r.err;
  fs::create_directory(dir_ + "/x.mp4");
  r = Ecrf({"render", kScene, "--orbit", "2", "--video", dir_ + "/x.mp4"});
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find(dir_ + "/x.mp4: is a directory"), std::string::npos) << r.err;
  EXPECT_EQ(Listing(dir_), std::vector<std::string>{"x.mp4"});
}

TEST_F(RenderVideo, UsageErrors) {
  Output r = Ecrf({"render", kScene, "--orbit", "2"});
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("needs -o DIR for PNGs or --video FILE.mp4"), std::string::npos) << r.err;
  r = Ecrf({"render", kScene, "--orbit", "2", "--spiral", "3", "-o", dir_});
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("give one camera source, not --orbit and --spiral"), std::string::npos)
      << r.err;
  r = Ecrf({"render", kScene, "--views", "d/transforms_test.json", "--video", dir_ + "/v.mp4"});
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("--video needs a camera path"), std::string::npos) << r.err;
  r = Ecrf({"render", kScene, "--spiral", "3", "--elevation", "80", "-o", dir_});
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("--elevation 80 with --spiral-elevation 15 reaches 95 degrees"),
            std::string::npos)
      << r.err;
  r = Ecrf({"render", kScene, "--orbit", "2", "-W", "1", "--video", dir_ + "/v.mp4"});
  EXPECT_EQ(r.rc, 2);
  EXPECT_NE(r.err.find("a video needs at least 2x2 pixels"), std::string::npos) << r.err;
  EXPECT_TRUE(Listing(dir_).empty());
}

TEST_F(RenderVideo, HelpDescribesPathsAndVideo) {
  const Output r = Ecrf({"render", "--help"});
  EXPECT_EQ(r.rc, 0);
  for (const char* text :
       {"--spiral N", "--path FILE", "--save-path FILE", "--video FILE.mp4", "--fps N:INT",
        "--ffmpeg PROGRAM", "--spiral-elevation DEG", "--spiral-radius F", "--spiral-cycles C",
        "azimuth 360 t", "elevation = --elevation + --spiral-elevation * p",
        "radius = --radius * (1 + --spiral-radius * p)", "transform_matrix"}) {
    EXPECT_NE(r.out.find(text), std::string::npos) << text << "\n" << r.out;
  }
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
