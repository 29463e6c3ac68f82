// `sirl submit` and `sirl status`: a profile as a Slurm job (an array of shards, or one MPI
// allocation) sized from `sirl plan`'s prediction, and what became of each shard.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "app/cluster_options.h"
#include "app/commands.h"
#include "experiment/plan.h"
#include "experiment/task_digest.h"
#include "jobs/cluster_prediction.h"
#include "jobs/estimate.h"
#include "jobs/progress.h"
#include "jobs/run.h"
#include "jobs/slurm_submission.h"
#include "jobs/stop_request.h"
#include "results/durable.h"
#include "results/results_file.h"
#include "results/task_store.h"

namespace sirl::app {

namespace fs = std::filesystem;

namespace {

struct SubmitOptions {
  std::string profile, out, sirl, partition, account;
  int shards = 4, cpus = 0, signal_seconds = 300;
  PlanClusterOptions cluster;
  double time_factor = 1.5, checkpoint_minutes = 5;
  bool now = false, rerun_failed = false, force = false;
};

SubmitOptions& submit_options() {
  static SubmitOptions o;
  return o;
}

// Runs a shell command; its standard output, or a UsageError with what it printed.
std::string run_capture(const std::string& command) {
  std::FILE* f = popen((command + " 2>&1").c_str(), "r");
  if (!f) throw std::runtime_error("cannot run " + command);
  std::string out;
  char buf[4096];
  while (size_t n = std::fread(buf, 1, sizeof buf, f)) out.append(buf, n);
  const int rc = pclose(f);
  if (rc != 0) {
    while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
    throw UsageError("`" + command + "` failed: " + (out.empty() ? "no output" : out));
  }
  return out;
}

// Submits the script (array: only the given indices, "" = the script's own --array); the job id.
std::string sbatch(const SlurmSubmission& s, const std::string& indices) {
  std::string cmd = "sbatch --parsable";
  if (!indices.empty()) cmd += " --array=" + indices;
  std::string id = run_capture(cmd + " " + sh_quote(s.script_path().string()));
  id = id.substr(0, id.find_first_of(";\n"));
  if (id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
    throw UsageError("sbatch printed no job id ('" + id + "')");
  return id;
}

// Each job's state in Slurm's queue ("PENDING", "RUNNING", ...; array tasks as "ID_i"), for the
// jobs still known there. `known` false (and nothing) when no Slurm answers here within 20 s (a
// client whose controller is down or whose slurm.conf is missing retries for a minute).
std::map<std::string, std::string> queue_states(const SlurmSubmission& s, bool& known) {
  std::map<std::string, std::string> states;
  known = std::system("timeout 20 sinfo -h -o %a >/dev/null 2>&1") == 0;
  if (!known) return states;
  for (const std::string& job : s.jobs) {
    std::string out;
    try {
      out = run_capture("squeue -h -r -o '%i %T' -j " + job);
    } catch (const UsageError&) {
      continue;  // purged from the queue
    }
    std::istringstream lines(out);
    std::string id, state;
    while (lines >> id >> state) states[id] = state;
  }
  return states;
}

bool live(const std::string& state) {
  static const std::set<std::string> done = {"COMPLETED", "FAILED",    "CANCELLED",
                                             "TIMEOUT",   "NODE_FAIL", "OUT_OF_MEMORY",
                                             "BOOT_FAIL", "DEADLINE",  "PREEMPTED"};
  return !state.empty() && !done.count(state);
}

struct ShardReport {
  ShardState state;
  bool complete = false;  // its results file is whole and checksummed
  int tasks = 0, committed = 0, checkpoints = 0;
  std::string queue;  // its job's state in Slurm's queue ("" = not there)
  // Its tasks not committed yet, and whether a training of each saved a checkpoint.
  std::vector<std::pair<std::string, bool>> open;
};

std::set<std::string> digests_in(const fs::path& dir) {
  std::set<std::string> d;
  for (const std::string& id : TaskStore::ids_in(dir)) d.insert(id.substr(0, id.find('-')));
  return d;
}

std::vector<ShardReport> shard_reports(const SlurmSubmission& s, bool& queue_known) {
  const Profile p = load_or_usage(s.profile_path().string());
  const Plan plan = make_plan(p);
  const std::vector<std::string> digests = task_digests(plan);
  const std::set<std::string> committed = digests_in(s.cache_path());
  const std::set<std::string> saved = digests_in(s.cache_path() / "checkpoints");
  const std::map<std::string, std::string> queue = queue_states(s, queue_known);
  std::vector<ShardReport> reports(size_t(s.shards));
  for (int i = 0; i < s.shards; ++i) {
    ShardReport& r = reports[size_t(i)];
    r.state = read_shard_state(s, i);
    const std::vector<char> mine = shard_tasks(plan, i, s.mpi ? 1 : s.shards);
    for (size_t t = 0; t < plan.tasks.size(); ++t) {
      if (!mine[t]) continue;
      ++r.tasks;
      const bool done = committed.count(digests[t]) > 0, started = saved.count(digests[t]) > 0;
      r.committed += int(done);
      r.checkpoints += int(started);
      if (!done) r.open.emplace_back(plan.tasks[t].key, started);
    }
    try {
      const RunInfo info = read_run_info(s.shard_file(i).string());
      r.complete = info.complete && info.verified;
    } catch (const std::exception&) {
    }
    for (const std::string& job : s.jobs) {
      const std::string id = s.mpi ? job : job + "_" + std::to_string(i);
      if (auto it = queue.find(id); it != queue.end() && live(it->second)) r.queue = it->second;
    }
  }
  return reports;
}

// Shards that need another job: not complete and no job of theirs pending or running.
std::vector<int> shards_to_rerun(const std::vector<ShardReport>& reports) {
  std::vector<int> v;
  for (size_t i = 0; i < reports.size(); ++i)
    if (!reports[i].complete && reports[i].queue.empty()) v.push_back(int(i));
  return v;
}

std::string index_list(const std::vector<int>& v) {
  std::string s;
  for (int i : v) s += (s.empty() ? "" : ",") + std::to_string(i);
  return s;
}

constexpr double kMiB = 1024.0 * 1024.0;

// --time and --mem from the prediction: the longest shard (or the MPI run) times the factor,
// plus the warning's lead and five minutes; the largest memory × 1.25 + 512 MiB (the process,
// its libraries, writing the results file).
void size_submission(SlurmSubmission& s, const Plan& plan, const PlanEstimate& e,
                     const SubmitOptions& o) {
  double longest = 0, shortest = 1e300, memory = 0;
  if (s.mpi) {
    PlanClusterOptions c = o.cluster;
    c.mpi = true;
    c.cores_per_node = s.cpus;
    const ClusterPrediction r =
        predict_cluster(plan, e, cluster_model(c), std::vector<char>(plan.tasks.size(), 1));
    longest = shortest = r.wall_seconds;
    memory = r.memory_bytes_per_node;
    std::printf(
        "predicted: %s on %d node(s) x %d cores (as `sirl plan %s --nodes %d --cores-per-node "
        "%d --threads-per-worker %d` predicts), memory per node %.0f MiB\n",
        format_duration(longest).c_str(), s.nodes, s.cpus, s.profile.c_str(), s.nodes, s.cpus,
        s.threads_per_worker, memory / kMiB);
  } else {
    PlanClusterOptions c;
    c.cores_per_node = s.cpus;
    const ClusterModel m = cluster_model(c);
    for (int i = 0; i < s.shards; ++i) {
      const ClusterPrediction r = predict_cluster(plan, e, m, shard_tasks(plan, i, s.shards));
      longest = std::max(longest, r.wall_seconds);
      shortest = std::min(shortest, r.wall_seconds);
      memory = std::max(memory, r.memory_bytes_per_node);
    }
    std::printf("predicted per shard on %d cores: %s to %s, memory up to %.0f MiB\n", s.cpus,
                format_duration(shortest).c_str(), format_duration(longest).c_str(), memory / kMiB);
  }
  s.time_minutes = int(std::ceil((o.time_factor * longest + s.signal_seconds) / 60.0)) + 5;
  s.memory_mib = int(std::ceil(1.25 * memory / kMiB)) + 512;
  std::printf(
      "requested: --time=%s (%.2f x the %s + %d s of warning + 5 min), --mem=%dM (1.25 x + 512 "
      "MiB)\n",
      slurm_time(s.time_minutes).c_str(), o.time_factor, s.mpi ? "run" : "longest shard",
      s.signal_seconds, s.memory_mib);
}

// A folder that already holds a submission: the same profile may be submitted again (finished
// tasks are reused); another profile, or one whose jobs still run, only with --force.
void check_folder(const SlurmSubmission& s, const Profile& p, bool force) {
  if (force || !fs::exists(s.manifest_path())) return;
  std::string text;
  {
    std::FILE* f = std::fopen(s.profile_path().c_str(), "rb");
    char buf[4096];
    while (f && !std::feof(f)) text.append(buf, std::fread(buf, 1, sizeof buf, f));
    if (f) std::fclose(f);
  }
  if (text != p.text)
    throw UsageError(s.dir.string() +
                     " holds a submission of another profile (or of another version of it): "
                     "choose another --out, or --force to replace it");
  bool known = false;
  SlurmSubmission old;
  try {
    old = read_submission(s.dir);
  } catch (const std::runtime_error& e) {
    throw UsageError(std::string(e.what()) + " (--force replaces it)");
  }
  for (const auto& [id, state] : queue_states(old, known))
    if (live(state))
      throw UsageError("job " + id + " of the submission in " + s.dir.string() + " is still " +
                       state + ": wait for it, cancel it (scancel), or --force");
}

std::string this_executable() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find this executable's path: give --sirl PATH");
  return exe.string();
}

SlurmSubmission prepare(const SubmitOptions& o, const Profile& p) {
  SlurmSubmission s;
  s.profile = p.name;
  s.dir = fs::absolute(o.out.empty() ? "out/" + p.name + "-slurm" : o.out).lexically_normal();
  s.sirl = o.sirl.empty() ? this_executable() : fs::absolute(o.sirl).string();
  s.mpi = o.cluster.mpi || o.cluster.nodes > 1;
  s.shards = s.mpi ? 1 : o.shards;
  s.nodes = o.cluster.nodes;
  s.cpus = s.mpi ? (o.cluster.cores_per_node > 0 ? o.cluster.cores_per_node : default_threads())
                 : (o.cpus > 0 ? o.cpus : default_threads());
  s.threads_per_worker = o.cluster.threads_per_worker;
  s.signal_seconds = o.signal_seconds;
  s.checkpoint_minutes = o.checkpoint_minutes;
  s.partition = o.partition;
  s.account = o.account;
  return s;
}

int submit_new(const SubmitOptions& o) {
  const Profile p = load_or_usage(o.profile);
  if (!is_plain_name(p.name))  // not echoed: it may hold a newline
    throw UsageError(
        "the profile's name cannot name a Slurm job and its files: use letters, "
        "digits, '.', '_' and '-' only (" +
        o.profile + ")");
  SlurmSubmission s = prepare(o, p);
  check_folder(s, p, o.force);
  const Plan plan = make_plan(p);
  std::printf("sirl submit: profile %s, %zu tasks, %s\n", p.name.c_str(), plan.tasks.size(),
              s.mpi ? ("one MPI job of " + std::to_string(s.nodes) + " node(s)").c_str()
                    : ("a job array of " + std::to_string(s.shards) + " shard(s)").c_str());
  std::fflush(stdout);
  std::fprintf(stderr, "calibrating on this machine (the prediction's task rates)...\n");
  const PlanEstimate e = estimate_plan(plan, p, s.cpus);
  try {
    size_submission(s, plan, e, o);
  } catch (const std::invalid_argument& x) {
    throw UsageError(x.what());
  }
  for (const char* sub : {"logs", "state"}) fs::create_directories(s.dir / sub);
  write_text_atomically(s.profile_path().string(), p.text);
  write_text_atomically(s.script_path().string(), slurm_script(s));
  fs::permissions(s.script_path(), fs::perms::owner_exec | fs::perms::group_exec,
                  fs::perm_options::add);
  write_submission(s);
  std::printf("wrote %s (and profile.toml, submission.toml beside it)\n", s.script_path().c_str());
  if (o.now) {
    s.jobs.push_back(sbatch(s, ""));
    write_submission(s);
    std::printf("submitted: job %s\n", s.jobs.back().c_str());
  } else {
    std::printf("submit it: sbatch %s   (or add --now)\n", s.script_path().c_str());
  }
  std::printf("then: sirl status %s", s.dir.c_str());
  if (!s.mpi)
    std::printf(";  sirl merge %s/%s.h5 %s/shard-*.h5", s.dir.c_str(), p.name.c_str(),
                s.dir.c_str());
  std::printf("\n");
  return 0;
}

int rerun_failed(const SubmitOptions& o) {
  if (o.out.empty()) throw UsageError("--rerun-failed needs --out: the submission's folder");
  SlurmSubmission s;
  try {
    s = read_submission(fs::absolute(o.out).lexically_normal());
  } catch (const std::runtime_error& e) {
    throw UsageError(e.what());
  }
  bool known = false;
  const std::vector<int> again = shards_to_rerun(shard_reports(s, known));
  if (!known)
    throw UsageError(
        "no Slurm answers here (sinfo failed or gave no answer in 20 s): cannot tell which shards "
        "still run");
  if (again.empty()) {
    std::printf("sirl submit: nothing to rerun in %s (every shard is complete or queued)\n",
                s.dir.c_str());
    return 0;
  }
  s.jobs.push_back(sbatch(s, s.mpi ? "" : index_list(again)));
  write_submission(s);
  std::printf("sirl submit: resubmitted %s %s as job %s\n", s.mpi ? "the run" : "shards",
              s.mpi ? "" : index_list(again).c_str(), s.jobs.back().c_str());
  return 0;
}

// A shard's state as print_status names it: complete, a phase (with its exit code when it failed
// or stopped), or lost (its log says running, the queue has no job of it).
std::string shard_state_name(const ShardReport& r, bool known) {
  std::string state = r.complete ? "complete" : phase_name(r.state.phase);
  if (!r.complete &&
      (r.state.phase == ShardState::kFailed || r.state.phase == ShardState::kStopped))
    state += " (" + std::to_string(r.state.exit_code) + ")";
  if (!r.complete && known && r.queue.empty() && r.state.phase == ShardState::kRunning)
    state = "lost";
  return state;
}

// `sirl status --json`: the table below as one JSON object.
void print_status_json(const SlurmSubmission& s, const std::vector<ShardReport>& reports,
                       bool known) {
  nlohmann::json j{{"dir", s.dir.string()},
                   {"profile", s.profile},
                   {"mpi", s.mpi},
                   {"jobs", s.jobs},
                   {"queue_known", known}};
  j["shards"] = nlohmann::json::array();
  for (const ShardReport& r : reports) {
    nlohmann::json open = nlohmann::json::array();
    for (const auto& [key, started] : r.open)
      open.push_back({{"key", key}, {"checkpoint", started}});
    j["shards"].push_back({{"state", shard_state_name(r, known)},
                           {"complete", r.complete},
                           {"tasks", r.tasks},
                           {"committed", r.committed},
                           {"checkpoints", r.checkpoints},
                           {"starts", r.state.starts},
                           {"queue", r.queue},
                           {"job", r.state.job},
                           {"host", r.state.host},
                           {"when", r.state.when},
                           {"open_tasks", open}});
  }
  j["rerun"] = shards_to_rerun(reports);
  std::printf("%s\n", j.dump(1, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
}

void print_status(const SlurmSubmission& s, const std::vector<ShardReport>& reports, bool known) {
  std::printf("submission %s: profile %s, %s, jobs %s\n", s.dir.c_str(), s.profile.c_str(),
              s.mpi ? "one MPI run" : (std::to_string(s.shards) + " shards").c_str(),
              s.jobs.empty() ? "none submitted yet" : [&] {
                std::string j;
                for (const auto& id : s.jobs) j += (j.empty() ? "" : ", ") + id;
                return j;
              }().c_str());
  std::printf("%-6s %-12s %-16s %-11s %-8s %-14s %s\n", "shard", "state", "tasks committed",
              "checkpoints", "starts", "in the queue", "last event");
  int complete = 0;
  for (size_t i = 0; i < reports.size(); ++i) {
    const ShardReport& r = reports[i];
    // A log that says "running" with no job in the queue: the job died without a word
    // (killed, node lost).
    const std::string state = shard_state_name(r, known);
    complete += r.complete;
    char tasks[32];
    std::snprintf(tasks, sizeof tasks, "%d/%d", r.committed, r.tasks);
    std::printf("%-6zu %-12s %-16s %-11d %-8d %-14s %s\n", i, state.c_str(), tasks, r.checkpoints,
                r.state.starts, known ? (r.queue.empty() ? "-" : r.queue.c_str()) : "(no Slurm)",
                r.state.job.empty()
                    ? "-"
                    : (r.state.job + " on " + r.state.host + ", " + r.state.when).c_str());
  }
  std::printf("%d of %zu complete", complete, reports.size());
  const std::vector<int> again = shards_to_rerun(reports);
  if (known && !again.empty() && complete < int(reports.size()))
    std::printf("; not complete and not queued: %s (sirl submit --rerun-failed --out %s)",
                index_list(again).c_str(), s.dir.c_str());
  std::printf("\n");
}

}  // namespace

void register_submit(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand(
      "submit",
      "Write a Slurm batch script for a profile, sized from `sirl plan`'s prediction, and with\n"
      "--now submit it: a job array of --shards (each `sirl run --shard i/n`, sharing one task\n"
      "cache), or with --nodes/--mpi one allocation running `mpirun sirl run`. Output, logs, the\n"
      "cache and checkpoints all go under --out. Jobs requeue themselves before their time\n"
      "limit and on pre-emption, continuing each training from its checkpoint.\n"
      "`sirl status DIR` shows every shard; --rerun-failed resubmits exactly the shards that\n"
      "are neither complete nor queued.");
  SubmitOptions& o = submit_options();
  cmd->add_option("profile", o.profile,
                  "Profile: a name in configs/ (" + bundled_profile_names() + ") or a .toml path");
  cmd->add_option("--out", o.out, "The submission's folder (default: out/PROFILE-slurm)")
      ->type_name("DIR")
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            std::error_code ec;
            if (v.empty()) return "must name a folder, got an empty path";
            if (std::filesystem::exists(v, ec) && !std::filesystem::is_directory(v, ec))
              return "must name a folder (new or a submission's), got the file '" + v + "'";
            return "";
          },
          "DIR", "submission_folder"));
  CLI::Option* shards =
      cmd->add_option("--shards", o.shards, "Array tasks: the plan split into this many shards")
          ->check(CLI::Range(1, 100000))
          ->capture_default_str();
  cmd->add_option("--cpus-per-task", o.cpus, "Cores of each array task (default: this machine's)")
      ->check(CLI::Range(1, 4096));
  auto* g =
      cmd->add_option_group("MPI", "One allocation running mpirun (as `sirl plan` models it)");
  g->add_option("--nodes", o.cluster.nodes, "Nodes (more than one implies --mpi)")
      ->check(CLI::Range(1, 100000));
  g->add_option("--cores-per-node", o.cluster.cores_per_node,
                "Cores per node (default: this machine's)")
      ->check(CLI::Range(1, 4096));
  g->add_flag("--mpi", o.cluster.mpi, "One MPI allocation instead of a job array");
  g->add_option("--threads-per-worker", o.cluster.threads_per_worker,
                "Cores each worker rank's tasks use")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  cmd->add_option("--time-factor", o.time_factor,
                  "--time is this many times the predicted time (plus the warning and 5 min)")
      ->check(CLI::Range(1.0, 100.0))
      ->capture_default_str();
  cmd->add_option("--signal-seconds", o.signal_seconds,
                  "SIGUSR1 this long before the time limit: save, stop, requeue (Slurm may send "
                  "it up to 60 s early)")
      ->check(CLI::Range(60, 86400))
      ->capture_default_str();
  cmd->add_option("--checkpoint-minutes", o.checkpoint_minutes,
                  "How often a running training saves its state besides the warning (sirl run)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  cmd->add_option("--partition", o.partition, "Slurm partition (default: the cluster's)");
  cmd->add_option("--account", o.account, "Slurm account (default: yours)");
  cmd->add_option("--sirl", o.sirl, "The sirl executable the jobs run (default: this one)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--now", o.now, "Submit with sbatch after writing the script");
  cmd->add_flag("--rerun-failed", o.rerun_failed,
                "Resubmit the shards of the submission in --out that are neither complete nor "
                "queued (failed, lost, stopped), with the same seeds; no PROFILE");
  cmd->add_flag("--force", o.force,
                "Write into a folder holding another profile's submission, or one whose jobs "
                "still run");
  add_set_option(cmd);
  run = [shards] {
    const SubmitOptions& o = submit_options();
    if (o.rerun_failed) {
      if (!o.profile.empty() || !profile_settings().empty())
        throw UsageError(
            "--rerun-failed reads the profile from --out's submission: give no PROFILE and no "
            "--set");
      return rerun_failed(o);
    }
    if (o.profile.empty()) throw UsageError("name a profile to submit (or --rerun-failed)");
    if ((o.cluster.mpi || o.cluster.nodes > 1) && shards->count() > 0)
      throw UsageError("--shards makes a job array; --nodes/--mpi one MPI job: give one of them");
    return submit_new(o);
  };
}

void register_status(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand(
      "status",
      "Show what became of a submission's shards (sirl submit --out DIR): complete, running,\n"
      "stopped to be requeued, failed (with the exit code), lost (its log says running but no\n"
      "job is queued), with their committed tasks and saved checkpoints.");
  static std::string dir;
  static bool tasks = false;
  cmd->add_option("dir", dir, "The submission's folder")->required()->check(CLI::ExistingDirectory);
  cmd->add_flag("--tasks", tasks,
                "Also list each incomplete shard's tasks not committed yet, marking those whose "
                "training saved a checkpoint (in progress, or stopped mid-way)");
  static bool as_json = false;
  cmd->add_flag("--json", as_json, "Print one JSON object instead (every shard, its open tasks)");
  run = [] {
    SlurmSubmission s;
    try {
      s = read_submission(fs::absolute(dir).lexically_normal());
    } catch (const std::runtime_error& e) {
      throw UsageError(e.what());
    }
    bool known = false;
    const std::vector<ShardReport> reports = shard_reports(s, known);
    if (as_json) {
      print_status_json(s, reports, known);
      return 0;
    }
    print_status(s, reports, known);
    if (tasks)
      for (size_t i = 0; i < reports.size(); ++i) {
        if (reports[i].complete || reports[i].open.empty()) continue;
        std::printf("\nshard %zu: %zu task(s) not committed\n", i, reports[i].open.size());
        for (const auto& [key, started] : reports[i].open)
          std::printf("  %s%s\n", key.c_str(), started ? "  (checkpoint saved)" : "");
      }
    return 0;
  };
}

}  // namespace sirl::app
