// `ecrf report sweep --plan`: a sweep as a plan of independent tasks, one `ecrf train` command line
// per point, for a batch system to run: a Slurm job array (sweep.sbatch), GNU parallel or one
// after another on this machine (run_local.sh). Each task writes the run directory the sweep
// itself would write, so `ecrf report sweep ... --collect` (collect.sh) reports finished tasks
// exactly as local runs, and names the log of any task that did not finish. Nothing here
// schedules work: Slurm (or parallel) does.
#ifndef ECRF_TOOLS_REPORT_SWEEP_PLAN_H_
#define ECRF_TOOLS_REPORT_SWEEP_PLAN_H_

#include <string>
#include <vector>

namespace ecrf {
namespace tools {

struct PlannedTask {
  std::string name;                     // the point's run name, e.g. rate_low
  std::string run_dir;                  // REPORT/runs/NAME, as the sweep's command line gave it
  std::vector<std::string> train_args;  // `ecrf train` arguments, without -o and --threads
};

struct SweepPlan {
  std::string plan_dir;  // REPORT/plan
  std::string ecrf;      // absolute path of the ecrf program the tasks run
  std::string work_dir;  // absolute directory the sweep's relative paths are relative to
  std::string job_name;  // Slurm job name
  int task_cpus = 4;     // --cpus-per-task of each array task (and its training threads)
  std::string task_mem = "8G";
  std::vector<PlannedTask> tasks;
  std::vector<std::string> collect_args;  // `ecrf` arguments that collect the report
};

// Writes plan_dir/{plan.json, task_K.sh, tasks.txt, sweep.sbatch, run_local.sh, collect.sh} and
// plan_dir/logs/ (each file through a temporary and a rename). Throws std::runtime_error naming
// the path on failure.
void WriteSweepPlan(const SweepPlan& plan);

// Where task k of a plan writes its log (sweep.sbatch and run_local.sh alike).
std::string TaskLogPath(const std::string& plan_dir, size_t k);

// `text` quoted for a POSIX shell (single quotes; a quote inside becomes '\'').
std::string ShellQuote(const std::string& text);

// The last `lines` lines of a text file ("" when it cannot be read).
std::string LastLines(const std::string& path, int lines);

}  // namespace tools
}  // namespace ecrf

#endif  // ECRF_TOOLS_REPORT_SWEEP_PLAN_H_
