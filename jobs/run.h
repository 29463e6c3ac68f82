// `sirl run`: plan → resume check → parallel execution with per-task commits → results file.
#pragma once
#include <filesystem>
#include <map>
#include <string>

#include "results/results_file.h"

#include "experiment/plan.h"
#include "experiment/profile.h"

namespace sirl {

struct RunOptions {
  std::string out;  // results file (HDF5)
  int threads = 0;  // 0 = every core
  // The most cores one task's kernels may use when nothing else is ready to run (the tail of a
  // run) or its chain would outlast the rest of the work (jobs/scheduler.h); 0 = all
  // `threads`, 1 = one core per task. Under MPI: the cores every
  // worker rank's tasks use (0 = 1). Results do not depend on it.
  int max_task_threads = 0;
  // The task cache (jobs/task_cache.h): finished tasks by content, shared by any runs given the
  // same folder; "" = OUT.tasks beside the output.
  std::string cache;
  // Reuse results computed on another CPU class (other bits) when this class has none.
  bool any_cpu_class = false;
  // Compute every task again (reusing nothing of the cache or of OUT), and accept an OUT written
  // for another shard.
  bool force = false;
  int shard_index = 0, shard_count = 1;  // run only shard i of n (Slurm job arrays)
  bool quiet = false;
  // Long trainings save their state this often (seconds, at an epoch's end) under
  // <cache>/checkpoints/, and a rerun continues them; 0: every epoch; negative: never.
  double checkpoint_seconds = 300;
  std::string engine_version, git_commit;  // recorded in the file
};

struct RunSummary {
  int tasks = 0, reused = 0, ran = 0;
  int elsewhere = 0;  // computed by another run sharing the cache while this one waited
  double seconds = 0;
  bool worker = false;  // an MPI worker rank (rank 0 reports for the run)
};

RunSummary run_profile(const Profile& p, const RunOptions& o);

// The folder of the task cache a run uses: --cache, or OUT.tasks beside the output.
std::filesystem::path cache_dir(const RunOptions& o);

// The policy for an existing results file at --out: its records are candidates for reuse (each
// still needs its task digest and CPU class to match, jobs/run.cpp) when a checksum verified it
// and it holds the same part of the grid (shard "" = the whole run); a file of another part is
// refused (`refusal` says why, one line) unless --force, which reuses nothing.
struct ResumeDecision {
  bool reuse = false;
  std::string refusal;  // non-empty: refuse the run with this text
};
ResumeDecision resume_decision(const RunInfo& existing, const std::string& shard, bool force);

// What a task cache folder already holds of a plan (read only: nothing created or removed).
struct CacheHoldings {
  int tasks = 0;        // results of this CPU class
  int other_class = 0;  // results only another class computed (reusable with --any-cpu-class)
  double flops = 0, other_flops = 0;  // their planned FLOPs
  std::vector<char> held;             // per plan task: its result (of this class) is there
};
CacheHoldings cache_holdings(const Plan& plan, const Profile& p, const std::filesystem::path& dir);

// Which of the plan's tasks belong to shard i of n: tasks are grouped by the representation
// they evaluate (a rep with its FPE/TPA cells stays together), groups are dealt by a hash of the
// rep key, and each shard adds the VAE tasks its groups depend on.
std::vector<char> shard_tasks(const Plan& plan, int index, int count);

// A results file at `out` from task records gathered elsewhere (`sirl merge`'s shards, the run
// `sirl evaluate --against` starts from): the records of p's plan, in plan order (others
// dropped), with p's datasets and tables, and `info` with the task counts and completeness set.
// Returns the number of records written.
size_t write_plan_records(const std::string& out, const Profile& p, RunInfo info,
                          const std::map<std::string, TaskRecord>& records);

// Parses "i/n" (0 ≤ i < n). Throws std::invalid_argument.
void parse_shard(const std::string& text, int& index, int& count);
// Throws std::runtime_error naming the first task (of those `mine` marks) whose estimated working
// set exceeds this machine's memory.
void refuse_tasks_beyond_memory(const Plan& plan, const std::vector<char>& mine);

}  // namespace sirl
