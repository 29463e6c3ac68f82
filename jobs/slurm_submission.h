// A profile submitted to Slurm (`sirl submit`): the batch script, the submission's manifest, and
// what each shard's log says about it. Everything lives in one output folder:
//   DIR/submission.toml        what was submitted (read back by `sirl status`, --rerun-failed)
//   DIR/profile.toml           the resolved profile every job runs (later edits change nothing)
//   DIR/sirl-<profile>.sbatch  the batch script
//   DIR/shard-<i>.h5           each array task's results (MPI: DIR/<profile>.h5)
//   DIR/tasks/                 the task cache the jobs share (commits, checkpoints)
//   DIR/state/shard-<i>.log    one line when a job starts, one when it ends (the script writes it)
//   DIR/logs/                  Slurm's output of every job, appended across requeues
#pragma once
#include <filesystem>
#include <string>
#include <vector>

namespace sirl {

struct SlurmSubmission {
  std::string profile;  // the profile's name
  std::filesystem::path dir;
  std::string sirl;            // absolute path of the sirl executable the jobs run
  bool mpi = false;            // one allocation with mpirun inside, instead of a job array
  int shards = 1;              // array tasks (1 under MPI)
  int nodes = 1;               // MPI: nodes of the allocation
  int cpus = 1;                // cores per array task, or per node under MPI
  int threads_per_worker = 1;  // MPI: cores of each worker rank
  int time_minutes = 60;       // --time
  int memory_mib = 1024;       // --mem: per array task, or per node under MPI
  int signal_seconds = 300;    // USR1 this long before the time limit
  double checkpoint_minutes = 5;
  std::string partition, account;  // "" = the cluster's default
  std::vector<std::string> jobs;   // Slurm job ids, in order of submission

  std::filesystem::path script_path() const;
  std::filesystem::path profile_path() const { return dir / "profile.toml"; }
  std::filesystem::path manifest_path() const { return dir / "submission.toml"; }
  std::filesystem::path cache_path() const { return dir / "tasks"; }
  // The results file of shard i (MPI: the run's one file).
  std::filesystem::path shard_file(int i) const;
  std::filesystem::path state_file(int i) const;
};

// Single-quoted for /bin/sh: any text, one word.
std::string shell_quoted(const std::string& s);

// A profile name that may name files and a Slurm job: letters, digits, '.', '_', '-' (not first),
// at most 128 characters. A submission refuses any other (a newline would add a line to the
// batch script, a '/' would write outside its folder).
bool is_plain_name(const std::string& name);

// Slurm's --time value for a duration, rounded up to a whole minute: "D-HH:MM:00".
std::string slurm_time(int minutes);

// The batch script: the job's resources as #SBATCH lines, then a shell that records the start,
// runs `sirl run` in the background (so its traps run at once), forwards SIGUSR1 (sent
// signal_seconds before the limit) and SIGTERM to it, records its exit, and requeues itself
// when sirl stopped on the time-limit warning (exit kExitStopped, jobs/stop_request.h). A
// pre-emption or `scontrol requeue` sends SIGTERM and requeues the job itself.
std::string slurm_script(const SlurmSubmission& s);

// The manifest, written atomically; and read back (throws std::runtime_error naming the file
// and the problem when it is missing or not one).
void write_submission(const SlurmSubmission& s);
SlurmSubmission read_submission(const std::filesystem::path& dir);

// What a shard's state log says: the last job that started it and how it ended.
struct ShardState {
  enum Phase { kNotStarted, kRunning, kStopped, kDone, kFailed } phase = kNotStarted;
  std::string job;  // the Slurm job (array task) of the last start
  std::string host, when;
  int exit_code = 0;  // kStopped, kDone, kFailed
  int starts = 0;     // how often it started (requeues included)
};
ShardState read_shard_state(const SlurmSubmission& s, int shard);
const char* phase_name(ShardState::Phase p);

}  // namespace sirl
