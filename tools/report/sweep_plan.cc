#include "tools/report/sweep_plan.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <deque>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "trainer/data/file_io.h"

namespace ecrf {
namespace tools {
namespace {

std::string TaskScriptPath(const std::string& plan_dir, size_t k) {
  return plan_dir + "/task_" + std::to_string(k) + ".sh";
}

std::string Join(const std::vector<std::string>& args) {
  std::string out;
  for (const std::string& a : args) out += (out.empty() ? "" : " ") + ShellQuote(a);
  return out;
}

void WriteScript(const std::string& path, const std::string& text) {
  trainer::WriteFileAtomically(path, text);
  if (chmod(path.c_str(), 0755) != 0) {
    throw std::runtime_error(path + ": cannot make it executable: " + std::strerror(errno));
  }
}

// Slurm reads #SBATCH lines word by word: a path with blanks or quotes cannot be given there.
void CheckPlainPath(const std::string& path) {
  for (char c : path) {
    if (c == ' ' || c == '\t' || c == '\n' || c == '\'' || c == '"' || c == '%') {
      throw std::runtime_error("--plan: the plan directory " + path +
                               " holds a blank, a quote or '%', which a Slurm batch script "
                               "cannot name; report into a plainer -o");
    }
  }
}

}  // namespace

std::string ShellQuote(const std::string& text) {
  bool plain = !text.empty();
  for (char c : text) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    std::strchr("-_./=:,@+", c) != nullptr;
    plain &= ok;
  }
  if (plain) return text;
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string TaskLogPath(const std::string& plan_dir, size_t k) {
  return plan_dir + "/logs/task_" + std::to_string(k) + ".log";
}

std::string LastLines(const std::string& path, int lines) {
  std::ifstream in(path);
  if (!in) return "";
  std::deque<std::string> last;
  std::string line;
  while (std::getline(in, line)) {
    // Progress bars rewrite one line with carriage returns: keep what was shown last.
    const size_t cr = line.find_last_of('\r', line.size() >= 2 ? line.size() - 2 : 0);
    if (cr != std::string::npos && cr + 1 < line.size()) line = line.substr(cr + 1);
    last.push_back(line);
    if (static_cast<int>(last.size()) > lines) last.pop_front();
  }
  std::string out;
  for (const std::string& l : last) out += l + "\n";
  return out;
}

namespace {

// The directory of the plan and its logs/.
void MakePlanDirectories(const std::string& dir) {
  for (const std::string& d : {dir, dir + "/logs"}) {
    if (mkdir(d.c_str(), 0755) != 0 && errno != EEXIST) {
      throw std::runtime_error(d + ": cannot create the plan directory: " + std::strerror(errno));
    }
  }
}

// The `ecrf` arguments of task k: the point's `ecrf train` line into its run directory.
std::vector<std::string> TaskArgs(const PlannedTask& t) {
  std::vector<std::string> args = {"train"};
  args.insert(args.end(), t.train_args.begin(), t.train_args.end());
  args.insert(args.end(), {"-o", t.run_dir});
  return args;
}

// task_K.sh: trains point k unless it has finished, on the threads the task was given.
std::string TaskScript(const SweepPlan& plan, size_t k, const std::vector<std::string>& args) {
  const PlannedTask& t = plan.tasks[k];
  const size_t n = plan.tasks.size();
  const std::string ecrf = ShellQuote(plan.ecrf), work = ShellQuote(plan.work_dir);
  return "#!/bin/sh\n"
         "# ecrf sweep task " +
         std::to_string(k) + " of " + std::to_string(n) + ": point " + t.name +
         ". Written by `ecrf report sweep --plan`; run by sweep.sbatch (Slurm array "
         "task " +
         std::to_string(k) +
         "), run_local.sh or by hand.\n"
         "# A finished point is left as it is; an interrupted one (Slurm's SIGTERM at the time "
         "limit, a preemption, Ctrl-C) continues from its checkpoint; any other starts afresh.\n"
         "# Threads: the Slurm task's CPUs, else $ECRF_THREADS, else all cores (the "
         "model is the same bits for any count).\n"
         "set -e\n"
         "cd " +
         work +
         "\n"
         "if [ -f " +
         ShellQuote(t.run_dir + "/metrics.json") +
         " ]; then\n"
         "  echo \"task " +
         std::to_string(k) + " (" + t.name + "): finished already in " + t.run_dir +
         "\"\n"
         "  exit 0\n"
         "fi\n"
         "ecrf=${ECRF:-" +
         ecrf +
         "}\n"
         "threads=${SLURM_CPUS_PER_TASK:-${ECRF_THREADS:-0}}\n"
         "start=--overwrite\n"
         "if [ -f " +
         ShellQuote(t.run_dir + "/checkpoint.ckpt") +
         " ]; then\n"
         "  start=--resume\n"
         "  echo \"task " +
         std::to_string(k) + " (" + t.name + "): continuing from " + t.run_dir +
         "/checkpoint.ckpt\"\n"
         "fi\n"
         "exec \"$ecrf\" " +
         Join(args) + " \"$start\" --threads \"$threads\"\n";
}

// Writes task_K.sh for every task and tasks.txt, one shell line per task (each task's script with
// its log); returns plan.json's entries of the tasks.
nlohmann::ordered_json WriteTasks(const SweepPlan& plan) {
  const std::string& dir = plan.plan_dir;
  nlohmann::ordered_json tasks = nlohmann::ordered_json::array();
  std::string task_lines;
  for (size_t k = 0; k < plan.tasks.size(); ++k) {
    const PlannedTask& t = plan.tasks[k];
    const std::vector<std::string> args = TaskArgs(t);
    const std::string script = TaskScriptPath(dir, k), log = TaskLogPath(dir, k);
    WriteScript(script, TaskScript(plan, k, args));
    task_lines += "bash " + ShellQuote(script) + " > " + ShellQuote(log) + " 2>&1\n";
    nlohmann::ordered_json j;
    j["index"] = k;
    j["name"] = t.name;
    j["run_dir"] = t.run_dir;
    j["script"] = script;
    j["log"] = log;
    j["command"] = "ecrf " + Join(args);
    tasks.push_back(j);
  }
  trainer::WriteFileAtomically(dir + "/tasks.txt", task_lines);
  return tasks;
}

// collect.sh: the sweep's command line with --collect.
std::string CollectScript(const SweepPlan& plan) {
  const std::string ecrf = ShellQuote(plan.ecrf), work = ShellQuote(plan.work_dir);
  const std::string collect = "ecrf=${ECRF:-" + ecrf + "}\ncd " + work + "\nexec \"$ecrf\" " +
                              Join(plan.collect_args) + "\n";
  return "#!/bin/sh\n"
         "# Collects the report of this plan: the sweep's command line with --collect. "
         "Finished runs are\n"
         "# reported as a local sweep reports them; a task that did not finish is named "
         "with its log\n"
         "# (exit status 1), and resubmitting the plan reruns only such tasks.\n" +
         collect;
}

// sweep.sbatch: a Slurm job array of the tasks.
std::string SbatchScript(const SweepPlan& plan) {
  const std::string& dir = plan.plan_dir;
  const size_t n = plan.tasks.size();
  const std::string last = std::to_string(n == 0 ? 0 : n - 1);
  return "#!/bin/bash\n"
         "#SBATCH --job-name=" +
         plan.job_name +
         "\n"
         "#SBATCH --array=0-" +
         last +
         "\n"
         "#SBATCH --cpus-per-task=" +
         std::to_string(plan.task_cpus) +
         "\n"
         "#SBATCH --mem=" +
         plan.task_mem +
         "\n"
         "#SBATCH --output=" +
         dir +
         "/logs/task_%a.log\n"
         "# One sweep point per array task (task_K.sh). Options given to sbatch override "
         "these lines:\n"
         "#   sbatch --partition=P --time=12:00:00 " +
         dir +
         "/sweep.sbatch\n"
         "# Afterwards: bash " +
         dir +
         "/collect.sh, or chained:\n"
         "#   jid=$(sbatch --parsable " +
         dir +
         "/sweep.sbatch)\n"
         "#   sbatch --dependency=afterany:$jid --wrap 'bash " +
         dir +
         "/collect.sh'\n"
         "# Finished points are skipped, so resubmitting reruns only the tasks that "
         "failed.\n"
         "exec bash " +
         dir + "/task_${SLURM_ARRAY_TASK_ID}.sh\n";
}

// run_local.sh: the tasks on this machine, one after another or with GNU parallel.
std::string RunLocalScript(const std::string& dir) {
  return "#!/bin/bash\n"
         "# Runs this plan on this machine: the tasks one after another, or JOBS at a "
         "time with GNU\n"
         "# parallel (bash run_local.sh [JOBS]; each task then trains on cores/JOBS "
         "threads), then\n"
         "# collects the report. Logs: " +
         dir +
         "/logs/task_K.log.\n"
         "set -u\n"
         "jobs=${1:-1}\n"
         "if [ \"$jobs\" -gt 1 ]; then\n"
         "  if ! command -v parallel >/dev/null 2>&1; then\n"
         "    echo \"run_local.sh: GNU parallel is not installed (apt-get install parallel);"
         " without JOBS the tasks run one after another\" >&2\n"
         "    exit 2\n"
         "  fi\n"
         "  export ECRF_THREADS=${ECRF_THREADS:-$(( $(nproc) / jobs > 0 ? $(nproc) / jobs : "
         "1 ))}\n"
         "  parallel --will-cite -j \"$jobs\" < " +
         ShellQuote(dir + "/tasks.txt") +
         "\n"
         "else\n"
         "  while IFS= read -r task; do\n"
         "    bash -c \"$task\" || echo \"run_local.sh: failed: $task\" >&2\n"
         "  done < " +
         ShellQuote(dir + "/tasks.txt") +
         "\n"
         "fi\n"
         "exec bash " +
         ShellQuote(dir + "/collect.sh") + "\n";
}

// plan.json: the plan as data (the tasks, how to submit, run and collect them).
void WritePlanJson(const SweepPlan& plan, const nlohmann::ordered_json& tasks) {
  const std::string& dir = plan.plan_dir;
  nlohmann::ordered_json j;
  j["ecrf"] = plan.ecrf;
  j["work_dir"] = plan.work_dir;
  j["job_name"] = plan.job_name;
  j["task_cpus"] = plan.task_cpus;
  j["task_mem"] = plan.task_mem;
  j["tasks"] = tasks;
  j["collect"] = "ecrf " + Join(plan.collect_args);
  j["slurm"] = "sbatch " + dir + "/sweep.sbatch";
  j["local"] = "bash " + dir + "/run_local.sh [JOBS]";
  trainer::WriteFileAtomically(dir + "/plan.json", j.dump(2) + "\n");
}

}  // namespace

void WriteSweepPlan(const SweepPlan& plan) {
  const std::string& dir = plan.plan_dir;
  CheckPlainPath(dir);
  MakePlanDirectories(dir);
  const nlohmann::ordered_json tasks = WriteTasks(plan);
  WriteScript(dir + "/collect.sh", CollectScript(plan));
  WriteScript(dir + "/sweep.sbatch", SbatchScript(plan));
  WriteScript(dir + "/run_local.sh", RunLocalScript(dir));
  WritePlanJson(plan, tasks);
}

}  // namespace tools
}  // namespace ecrf
