#include "jobs/slurm_submission.h"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include <toml++/toml.h>

#include "datasets/enum_names.h"
#include "jobs/stop_request.h"
#include "results/durable.h"

namespace sirl {

namespace fs = std::filesystem;

namespace {

std::string sbatch_lines(const SlurmSubmission& s) {
  std::ostringstream o;
  o << "#SBATCH --job-name=sirl-" << s.profile << "\n";
  if (s.mpi) {
    const int ranks = std::max(1, s.cpus / std::max(1, s.threads_per_worker));
    o << "#SBATCH --nodes=" << s.nodes << "\n"
      << "#SBATCH --ntasks-per-node=" << ranks << "\n"
      << "#SBATCH --cpus-per-task=" << s.threads_per_worker << "\n";
  } else {
    o << "#SBATCH --array=0-" << s.shards - 1 << "\n"
      << "#SBATCH --cpus-per-task=" << s.cpus << "\n";
  }
  o << "#SBATCH --mem=" << s.memory_mib << "M\n"
    << "#SBATCH --time=" << slurm_time(s.time_minutes) << "\n"
    << "#SBATCH --output=" << (s.dir / "logs").string() << (s.mpi ? "/%x-%j.out" : "/%x-%A_%a.out")
    << "\n"
    << "#SBATCH --open-mode=append\n"
    << "#SBATCH --requeue\n"
    << "#SBATCH --signal=B:USR1@" << s.signal_seconds << "\n";
  if (!s.partition.empty()) o << "#SBATCH --partition=" << s.partition << "\n";
  if (!s.account.empty()) o << "#SBATCH --account=" << s.account << "\n";
  return o.str();
}

}  // namespace

fs::path SlurmSubmission::script_path() const {
  return dir / ("sirl-" + profile + ".sbatch");
}

fs::path SlurmSubmission::shard_file(int i) const {
  return mpi ? dir / (profile + ".h5") : dir / ("shard-" + std::to_string(i) + ".h5");
}

fs::path SlurmSubmission::state_file(int i) const {
  return dir / "state" / ("shard-" + std::to_string(i) + ".log");
}

std::string shell_quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

bool is_plain_name(const std::string& name) {
  return !name.empty() && name.size() <= 128 && name.front() != '.' && name.front() != '-' &&
         name.find_first_not_of(
             "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789._-") ==
             std::string::npos;
}

std::string slurm_time(int minutes) {
  minutes = std::max(1, minutes);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%d-%02d:%02d:00", minutes / 1440, minutes / 60 % 24,
                minutes % 60);
  return buf;
}

std::string slurm_script(const SlurmSubmission& s) {
  std::ostringstream o;
  o << "#!/bin/bash\n"
    << "# Written by `sirl submit` for profile '" << s.profile << "': "
    << (s.mpi ? "one MPI allocation of " + std::to_string(s.nodes) + " node(s)"
              : "a job array of " + std::to_string(s.shards) + " shard(s)")
    << ".\n"
    << "# --time and --mem come from `sirl plan`'s prediction (with a margin). On SIGUSR1, sent\n"
    << "# " << s.signal_seconds
    << " s before the time limit, sirl saves every training in progress and exits " << kExitStopped
    << ",\n"
    << "# and this script requeues the job; a pre-emption (SIGTERM) requeues it by itself. A\n"
    << "# requeued job continues from the checkpoints. `sirl status " << s.dir.string()
    << "` shows\n"
    << "# every shard; `sirl submit --rerun-failed --out " << s.dir.string()
    << "` resubmits the failed ones.\n"
    << sbatch_lines(s) << "set -u\n"
    << "dir=" << shell_quoted(s.dir.string()) << "\n";
  if (s.mpi) {
    o << "shard=0\njob=\"$SLURM_JOB_ID\"\n";
  } else {
    o << "shard=\"${SLURM_ARRAY_TASK_ID:?submit this script with sbatch: it is a job array}\"\n"
      << "job=\"${SLURM_ARRAY_JOB_ID}_${shard}\"\n";
  }
  o << "state=\"$dir/state/shard-$shard.log\"\n"
    << "mkdir -p \"$dir/state\"\n"
    << "echo \"start $job $(hostname) $(date -u +%Y-%m-%dT%H:%M:%SZ)\" >> \"$state\"\n";
  const std::string common =
      " run \"$dir/profile.toml\" --cache \"$dir/tasks\" --checkpoint-minutes " + [&] {
        std::ostringstream c;
        c << s.checkpoint_minutes;
        return c.str();
      }();
  if (s.mpi) {
    // mpirun forwards SIGUSR1 to every rank. On SIGTERM it ends the ranks itself, killing them
    // a second later unless told to wait: give them the time to save (Slurm's KillWait still
    // bounds it). Ranks are not bound to one core so that a big task may borrow its node's idle
    // workers (sirl run --task-threads).
    o << "export OMPI_MCA_odls_base_sigkill_timeout=30\n"
      << "mpirun --bind-to none " << shell_quoted(s.sirl) << common << " --out "
      << shell_quoted(s.shard_file(0).string()) << " --task-threads " << s.threads_per_worker
      << " &\n";
  } else {
    o << shell_quoted(s.sirl) << common << " --shard \"$shard/" << s.shards
      << "\" --threads \"${SLURM_CPUS_PER_TASK:-" << s.cpus << "}\" \\\n"
      << "  --out \"$dir/shard-$shard.h5\" &\n";
  }
  o << "pid=$!\n"
    << "warned=0\n"
    << "trap 'warned=1; kill -USR1 \"$pid\" 2>/dev/null' USR1\n"
    << "trap 'kill -TERM \"$pid\" 2>/dev/null' TERM\n"
    << "# `wait` returns early when a trapped signal arrives: wait again while sirl runs.\n"
    << "while :; do\n"
    << "  wait \"$pid\"; rc=$?\n"
    << "  [ \"$rc\" -le 128 ] && break\n"
    << "  if ! kill -0 \"$pid\" 2>/dev/null; then\n"
    << "    wait \"$pid\" 2>/dev/null; again=$?; [ \"$again\" -ne 127 ] && rc=$again\n"
    << "    break\n"
    << "  fi\n"
    << "done\n"
    << "echo \"exit $rc $(date -u +%Y-%m-%dT%H:%M:%SZ)\" >> \"$state\"\n"
    << "if [ \"$rc\" -eq " << kExitStopped << " ] && [ \"$warned\" -eq 1 ]; then\n"
    << "  scontrol requeue \"$job\"  # the time limit is near: continue in a new job\n"
    << "  exit 0\n"
    << "fi\n"
    << "exit \"$rc\"\n";
  return o.str();
}

void write_submission(const SlurmSubmission& s) {
  toml::array jobs;
  for (const auto& j : s.jobs) jobs.push_back(j);
  const toml::table t{{"profile", s.profile},
                      {"sirl", s.sirl},
                      {"mpi", s.mpi},
                      {"shards", s.shards},
                      {"nodes", s.nodes},
                      {"cpus", s.cpus},
                      {"threads_per_worker", s.threads_per_worker},
                      {"time_minutes", s.time_minutes},
                      {"memory_mib", s.memory_mib},
                      {"signal_seconds", s.signal_seconds},
                      {"checkpoint_minutes", s.checkpoint_minutes},
                      {"partition", s.partition},
                      {"account", s.account},
                      {"jobs", jobs}};
  std::ostringstream o;
  o << "# sirl submit: what was submitted from this folder (read by `sirl status` and\n"
    << "# `sirl submit --rerun-failed`).\n"
    << t << "\n";
  write_text_atomically(s.manifest_path().string(), o.str());
}

SlurmSubmission read_submission(const fs::path& dir) {
  SlurmSubmission s;
  s.dir = dir;
  const fs::path file = s.manifest_path();
  if (!fs::exists(file))
    throw std::runtime_error(dir.string() +
                             " holds no submission (no submission.toml): give the --out "
                             "folder of a `sirl submit`");
  toml::table t;
  try {
    t = toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    throw std::runtime_error(file.string() +
                             " is not a submission manifest: " + std::string(e.description()));
  }
  auto need = [&](const char* key) -> toml::node& {
    toml::node* n = t.get(key);
    if (!n) throw std::runtime_error(file.string() + " lacks '" + key + "'");
    return *n;
  };
  auto integer = [&](const char* key, int lo) {
    const auto v = need(key).value<int64_t>();
    if (!v || *v < lo || *v > 1000000)
      throw std::runtime_error(file.string() + ": '" + key +
                               "' is not an integer >= " + std::to_string(lo));
    return int(*v);
  };
  auto text = [&](const char* key) {
    const auto v = need(key).value<std::string>();
    if (!v) throw std::runtime_error(file.string() + ": '" + key + "' is not a string");
    return *v;
  };
  s.profile = text("profile");
  s.sirl = text("sirl");
  s.mpi = need("mpi").value<bool>().value_or(false);
  s.shards = integer("shards", 1);
  s.nodes = integer("nodes", 1);
  s.cpus = integer("cpus", 1);
  s.threads_per_worker = integer("threads_per_worker", 1);
  s.time_minutes = integer("time_minutes", 1);
  s.memory_mib = integer("memory_mib", 1);
  s.signal_seconds = integer("signal_seconds", 0);
  s.checkpoint_minutes = need("checkpoint_minutes").value<double>().value_or(5);
  s.partition = text("partition");
  s.account = text("account");
  if (const toml::array* a = need("jobs").as_array())
    for (const auto& j : *a)
      if (auto v = j.value<std::string>()) s.jobs.push_back(*v);
  if (!is_plain_name(s.profile))
    throw std::runtime_error(file.string() + ": 'profile' is not a profile name");
  return s;
}

ShardState read_shard_state(const SlurmSubmission& s, int shard) {
  ShardState st;
  std::ifstream in(s.state_file(shard));
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string what;
    words >> what;
    if (what == "start") {
      words >> st.job >> st.host >> st.when;
      st.phase = ShardState::kRunning;
      ++st.starts;
    } else if (what == "exit") {
      int rc = -1;
      if (!(words >> rc)) continue;  // a torn line: the job was killed while writing it
      words >> st.when;
      st.exit_code = rc;
      st.phase = rc == 0              ? ShardState::kDone
                 : rc == kExitStopped ? ShardState::kStopped
                                      : ShardState::kFailed;
    }
  }
  return st;
}

namespace {
constexpr EnumName<ShardState::Phase> kPhaseNames[] = {
    {ShardState::kNotStarted, "not started"}, {ShardState::kRunning, "running"},
    {ShardState::kStopped, "stopped"},        {ShardState::kDone, "done"},
    {ShardState::kFailed, "failed"},
};
}  // namespace

const char* phase_name(ShardState::Phase p) {
  return name_in(kPhaseNames, p);
}

}  // namespace sirl
