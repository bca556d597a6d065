// COLMAP's progress lines (tools/prepare/colmap_progress.h), as COLMAP 3.8 prints them, and the
// progress `ecrf prepare` shows from them.
#include "tools/prepare/colmap_progress.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "tools/run_program.h"

namespace ecrf {
namespace tools {
namespace {

TEST(ColmapProgress, ReadsEachPhasesLines) {
  ColmapStep s;
  ASSERT_TRUE(ParseColmapProgress("Processed file [12/50]", 50, &s));
  EXPECT_EQ(s.done, 12);
  EXPECT_EQ(s.total, 50);
  // Exhaustive matching goes block by block: block (i, j) of N x M.
  ASSERT_TRUE(ParseColmapProgress("Matching block [2/3, 1/3] in 4.512s", 50, &s));
  EXPECT_EQ(s.done, 4);
  EXPECT_EQ(s.total, 9);
  ASSERT_TRUE(ParseColmapProgress("Matching block [1/1] in 0.5s", 50, &s));
  EXPECT_EQ(s.done, 1);
  EXPECT_EQ(s.total, 1);
  ASSERT_TRUE(ParseColmapProgress("Matching image [7/40] in 0.101s", 40, &s));
  EXPECT_EQ(s.done, 7);
  EXPECT_EQ(s.total, 40);
  // Mapping counts the registered images against the frames given.
  ASSERT_TRUE(ParseColmapProgress("  Registering image #31 (9)", 50, &s));
  EXPECT_EQ(s.done, 9);
  EXPECT_EQ(s.total, 50);
  for (const char* other :
       {"", "  Name:            frame_00012.jpg", "Elapsed time: 0.101 [minutes]",
        "Processed file [12/0]", "Matching block [x/3, 1/3]"}) {
    EXPECT_FALSE(ParseColmapProgress(other, 50, &s)) << other;
  }
}

TEST(ColmapProgress, ShowsDoneOfTotalAndTheEndInALog) {
  std::FILE* log = std::tmpfile();
  ASSERT_NE(log, nullptr);
  ColmapProgress progress("COLMAP feature extraction of 4 frames", 4, log);
  progress("Processed file [1/4]");  // the first line of a log waits 30 s unless it is the end
  progress("  Features:        8192");
  progress("Processed file [4/4]");
  progress.Finish();
  std::rewind(log);
  char text[512] = {0};
  const size_t n = std::fread(text, 1, sizeof(text) - 1, log);
  std::fclose(log);
  const std::string shown(text, n);
  EXPECT_EQ(shown, "prepare: COLMAP feature extraction of 4 frames: 4/4 (100%), 0m00s left\n");
}

// With a line callback RunProgram hands over each line of stdout and stderr as it comes, and
// the last line even without a newline; the tail for error messages still holds them.
TEST(RunProgram, EveryLineOfBothStreamsReachesTheCallback) {
  const std::string sh = FindExecutable("sh");
  ASSERT_FALSE(sh.empty());
  std::vector<std::string> lines;
  const ProgramResult r =
      RunProgram({sh, "-c", "echo one; echo two >&2; printf 'three\\rfour'; exit 3"},
                 [&lines](const std::string& line) { lines.push_back(line); });
  EXPECT_EQ(r.exit_status, 3);
  EXPECT_EQ(lines, (std::vector<std::string>{"one", "two", "three", "four"}));
  EXPECT_NE(r.error_tail.find("two"), std::string::npos);
  // Without one, stdout goes nowhere, as before.
  EXPECT_EQ(RunProgram({sh, "-c", "echo one; echo two >&2"}).error_tail, "two\n");
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
