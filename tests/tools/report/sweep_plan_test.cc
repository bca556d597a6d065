#include "tools/report/sweep_plan.h"
#include "tests/common/scoped_temp_dir.h"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace ecrf {
namespace tools {
namespace {

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(SweepPlan, ShellQuoteLeavesPlainWordsAndQuotesTheRest) {
  EXPECT_EQ(ShellQuote("--lambda-e"), "--lambda-e");
  EXPECT_EQ(ShellQuote("../data/chair"), "../data/chair");
  EXPECT_EQ(ShellQuote("a b"), "'a b'");
  EXPECT_EQ(ShellQuote("it's"), "'it'\\''s'");
  EXPECT_EQ(ShellQuote("$HOME"), "'$HOME'");
  EXPECT_EQ(ShellQuote(""), "''");
}

TEST(SweepPlan, WritesOneScriptPerTaskTheArrayAndTheCollector) {
  const testing_util::ScopedTempDir tmp("ecrf_plan_test");
  const std::string root = tmp.path();
  SweepPlan p;
  p.plan_dir = root + "/report/plan";
  ASSERT_EQ(mkdir((root + "/report").c_str(), 0755), 0);
  p.ecrf = "/opt/ecrf/bin/ecrf";
  p.work_dir = "/home/me/work dir";
  p.job_name = "ecrf-sweep-chair";
  p.task_cpus = 8;
  p.tasks = {{"rate_low", "report/runs/rate_low", {"--data", "../chair", "--rate", "low"}},
             {"target_316KB", "report/runs/target_316KB", {"--target-size", "316KB"}}};
  p.collect_args = {"report", "sweep", "--data", "../chair", "-o", "report", "--collect"};
  WriteSweepPlan(p);
  const std::string task1 = ReadText(p.plan_dir + "/task_1.sh");
  EXPECT_NE(task1.find("cd '/home/me/work dir'\n"), std::string::npos) << task1;
  EXPECT_NE(task1.find("if [ -f report/runs/target_316KB/metrics.json ]"), std::string::npos);
  EXPECT_NE(task1.find("exec \"$ecrf\" train --target-size 316KB -o report/runs/target_316KB "
                       "\"$start\" --threads \"$threads\""),
            std::string::npos)
      << task1;
  struct stat st;
  ASSERT_EQ(stat((p.plan_dir + "/task_1.sh").c_str(), &st), 0);
  EXPECT_TRUE(st.st_mode & S_IXUSR);
  const std::string sbatch = ReadText(p.plan_dir + "/sweep.sbatch");
  EXPECT_NE(sbatch.find("#SBATCH --array=0-1\n"), std::string::npos) << sbatch;
  EXPECT_NE(sbatch.find("#SBATCH --cpus-per-task=8\n"), std::string::npos);
  EXPECT_NE(sbatch.find("#SBATCH --output=" + p.plan_dir + "/logs/task_%a.log\n"),
            std::string::npos);
  EXPECT_NE(sbatch.find("exec bash " + p.plan_dir + "/task_${SLURM_ARRAY_TASK_ID}.sh"),
            std::string::npos);
  EXPECT_NE(
      ReadText(p.plan_dir + "/collect.sh").find("report sweep --data ../chair -o report --collect"),
      std::string::npos);
  EXPECT_EQ(ReadText(p.plan_dir + "/tasks.txt"),
            "bash " + p.plan_dir + "/task_0.sh > " + TaskLogPath(p.plan_dir, 0) + " 2>&1\n" +
                "bash " + p.plan_dir + "/task_1.sh > " + TaskLogPath(p.plan_dir, 1) + " 2>&1\n");
  EXPECT_NE(ReadText(p.plan_dir + "/plan.json").find("\"name\": \"target_316KB\""),
            std::string::npos);
  struct stat logs;
  EXPECT_EQ(stat((p.plan_dir + "/logs").c_str(), &logs), 0);
}

// A task killed at Slurm's time limit (or preempted) continues from its checkpoint when the array
// task runs again; without one it starts afresh, and a finished point is left alone. The script is
// run with ECRF pointing at echo, so it prints the command it would run.
TEST(SweepPlan, ATaskContinuesFromItsCheckpoint) {
  const testing_util::ScopedTempDir tmp("ecrf_plan_resume");
  const std::string root = tmp.path();
  SweepPlan p;
  p.plan_dir = root + "/plan";
  p.ecrf = "/nonexistent/ecrf";
  p.work_dir = root;
  p.job_name = "ecrf-sweep";
  p.tasks = {{"rate_low", "runs/rate_low", {"--rate", "low"}}};
  p.collect_args = {"report", "sweep", "--collect"};
  WriteSweepPlan(p);
  const std::string out = root + "/out.txt";
  auto run = [&] {
    const std::string cmd =
        "ECRF=/bin/echo ECRF_THREADS=3 sh '" + p.plan_dir + "/task_0.sh' > '" + out + "' 2>&1";
    EXPECT_EQ(std::system(cmd.c_str()), 0);
    return ReadText(out);
  };
  EXPECT_NE(run().find("train --rate low -o runs/rate_low --overwrite --threads 3"),
            std::string::npos)
      << ReadText(out);
  ASSERT_EQ(mkdir((root + "/runs").c_str(), 0755), 0);
  ASSERT_EQ(mkdir((root + "/runs/rate_low").c_str(), 0755), 0);
  std::ofstream(root + "/runs/rate_low/checkpoint.ckpt") << "x";
  const std::string resumed = run();
  EXPECT_NE(resumed.find("continuing from runs/rate_low/checkpoint.ckpt"), std::string::npos)
      << resumed;
  EXPECT_NE(resumed.find("train --rate low -o runs/rate_low --resume --threads 3"),
            std::string::npos)
      << resumed;
  std::ofstream(root + "/runs/rate_low/metrics.json") << "{}";
  EXPECT_NE(run().find("finished already"), std::string::npos) << ReadText(out);
}

TEST(SweepPlan, RefusesAPlanDirectorySlurmCannotName) {
  const testing_util::ScopedTempDir tmp("ecrf_plan_test");
  const std::string root = tmp.path();
  SweepPlan p;
  p.plan_dir = root + "/my report/plan";
  try {
    WriteSweepPlan(p);
    ADD_FAILURE() << "a plan directory with a blank was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("my report/plan"), std::string::npos) << e.what();
  }
}

TEST(SweepPlan, LastLinesKeepsWhatAProgressBarShowedLast) {
  const testing_util::ScopedTempDir tmp("ecrf_plan_test");
  const std::string path = tmp.path() + "/task_0.log";
  std::ofstream(path) << "one\ntwo\n[##  ] 10/20\r[####] 20/20\nerror: out of memory\n";
  EXPECT_EQ(LastLines(path, 2), "[####] 20/20\nerror: out of memory\n");
  EXPECT_EQ(LastLines(path + ".missing", 2), "");
}

}  // namespace
}  // namespace tools
}  // namespace ecrf
