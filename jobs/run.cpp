#include "jobs/run.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>

#include "jobs/mpi_run.h"
#include "jobs/progress.h"
#include "jobs/provenance.h"
#include "jobs/scheduler.h"
#include "jobs/task_checkpoints.h"
#include "jobs/task_kinds.h"
#include "jobs/task_runner.h"
#include "kernels/cpu_class.h"
#include "kernels/gemm_bf16.h"
#include "kernels/rng.h"
#include "kernels/roofline.h"
#include "results/durable.h"
#include "results/file_lock.h"
#include "results/h5.h"
#include "results/results_file.h"
#include "results/task_store.h"

namespace sirl {

namespace fs = std::filesystem;

namespace {

std::string now_iso() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string hostname() {
  char buf[256] = {};
  gethostname(buf, sizeof buf - 1);
  return buf;
}

// Whether the results file keeps a task's weights: the environment's store_weights (the user
// study's networks, regenerable and 3.1 M floats on JacoRobot, never).
bool keeps_weights(const Profile& p, const Task& t) {
  auto it = p.axes.find(t.env);
  return task_kind(t.kind).stores_weights && it != p.axes.end() && it->second.store_weights;
}

}  // namespace

size_t write_plan_records(const std::string& out, const Profile& p, RunInfo info,
                          const std::map<std::string, TaskRecord>& all) {
  const Plan plan = make_plan(p);
  std::vector<TaskRecord> records;
  for (const auto& t : plan.tasks)
    if (auto it = all.find(t.key); it != all.end()) records.push_back(it->second);
  info.tasks_total = int64_t(plan.tasks.size());
  info.tasks_done = int64_t(records.size());
  info.complete = records.size() == plan.tasks.size();
  RunContext ctx(p, [](const std::string& k) -> TaskRecord {
    throw std::logic_error("writing gathered records reads no task (" + k + ")");
  });
  std::vector<RunDataset> ds;
  for (const auto& env : p.envs)
    ds.push_back({&ctx.dataset(env), &ctx.bundle(env, p.axes.at(env).seeds.front())});
  write_results_file(out, info, ds, records, result_tables(records, info.roofs()));
  return records.size();
}

void parse_shard(const std::string& text, int& index, int& count) {
  const auto slash = text.find('/');
  try {
    // Digits, one slash, digits: nothing else (no spaces, signs or hex).
    if (slash == std::string::npos || slash == 0 || slash + 1 == text.size() || text.size() > 19 ||
        text.find_first_not_of("0123456789/") != std::string::npos ||
        text.find('/', slash + 1) != std::string::npos)
      throw std::invalid_argument("");
    size_t p1 = 0, p2 = 0;
    index = std::stoi(text.substr(0, slash), &p1);
    count = std::stoi(text.substr(slash + 1), &p2);
    if (p1 != slash || p2 != text.size() - slash - 1) throw std::invalid_argument("");
  } catch (const std::exception&) {
    throw std::invalid_argument("--shard must look like i/n (e.g. 0/4), got '" + text + "'");
  }
  if (count < 1 || index < 0 || index >= count)
    throw std::invalid_argument("--shard " + text + ": need 0 <= i < n");
}

std::vector<char> shard_tasks(const Plan& plan, int index, int count) {
  const int n = int(plan.tasks.size());
  std::vector<char> in(n, count == 1);
  if (count == 1) return in;
  for (int i = 0; i < n; ++i) {
    const std::string g = task_kind(plan.tasks[i].kind).shard_group(plan.tasks[i]);
    if (!g.empty()) in[i] = seed_from_key(g) % uint64_t(count) == uint64_t(index);
  }
  // Pull in dependencies (the VAEs), last task first so chains close.
  for (int i = n - 1; i >= 0; --i)
    if (in[i])
      for (int d : plan.tasks[i].deps) in[d] = 1;
  return in;
}

namespace {
RunSummary run_rank0(const Profile& p, const RunOptions& o, int mpi_size);
}

RunSummary run_profile(const Profile& p, const RunOptions& o) {
  if (o.out.empty()) throw std::invalid_argument("--out is required");
  if (!launched_under_mpi()) return run_rank0(p, o, 1);
  const auto [rank, size] = mpi_start();
  if (rank > 0) {
    // A worker: inputs of its tasks come from rank 0's commits (shared file system) or from the
    // results file of an earlier run.
    const Plan plan = make_plan(p);
    const fs::path staging = o.out + ".tasks";
    RunContext ctx(p, [&](const std::string& key) -> TaskRecord {
      try {
        return TaskStore::load_from(staging, key);
      } catch (const H5Error&) {
        H5File f = H5File::open_read(o.out);
        return read_record(f, "/runs/" + key);
      }
    });
    mpi_work(plan, ctx);
    mpi_stop();
    RunSummary s;
    s.worker = true;
    return s;
  }
  try {
    RunSummary s = run_rank0(p, o, size);
    mpi_stop();
    return s;
  } catch (...) {
    mpi_release_workers();  // workers waiting for a task exit instead of hanging
    mpi_stop();
    throw;
  }
}

ResumeDecision resume_decision(const RunInfo& existing, const std::string& profile_text,
                               const std::string& engine_version, const std::string& shard,
                               bool force) {
  auto part = [](const std::string& s) { return s.empty() ? "the whole run" : "shard " + s; };
  ResumeDecision d;
  const bool same_profile = existing.profile_text == profile_text,
             same_engine = existing.engine_version == engine_version,
             same_part = existing.shard == shard;
  if (!force) {
    if (!same_profile)
      d.refusal = "under a different profile ('" + existing.profile_name + "')";
    else if (!same_engine)
      d.refusal = "by engine " + existing.engine_version + " (this is " + engine_version + ")";
    else if (!same_part)  // writing another part would replace this file's tasks with that part's
      d.refusal = "with " + part(existing.shard) + " (" + std::to_string(existing.tasks_done) +
                  " tasks), and this run is " + part(shard);
    if (!d.refusal.empty()) return d;
  }
  d.reuse = same_profile && same_engine && same_part && existing.verified;
  return d;
}

namespace {

[[noreturn]] void refuse(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + " was written " + what +
                              "; rerun with --force to discard it, or choose another --out");
}

// Resume policy for the results file: its records count as done only when it was written by this
// profile, this engine and this part of the grid; otherwise the run is refused (or, with --force,
// starts over).
std::map<std::string, TaskRecord> load_prior(const Profile& p, const RunOptions& o,
                                             const std::string& shard) {
  std::map<std::string, TaskRecord> prior;
  if (!fs::exists(o.out)) return prior;
  RunInfo info;
  try {
    info = read_run_info(o.out);
  } catch (const H5Error& e) {
    if (!o.force) throw;
    std::fprintf(stderr, "sirl run: %s; --force: computing every task again\n", e.what());
    return prior;
  }
  const ResumeDecision d = resume_decision(info, p.text, o.engine_version, shard, o.force);
  if (!d.refusal.empty()) refuse(o.out, d.refusal);
  // Records are reused only from a file a checksum verified: the new file's checksum would
  // otherwise vouch for bytes nobody checked.
  if (!info.verified)
    std::fprintf(stderr, "sirl run: %s; its tasks are computed again\n",
                 unverified_note(o.out).c_str());
  if (d.reuse)
    for (auto& r : read_results_records(o.out)) prior[r.key] = std::move(r);
  return prior;
}

// The staging directory of committed tasks: kept when it belongs to this profile and engine (an
// interrupted run), refused or (--force) discarded otherwise. One without a committed task holds
// nothing to lose (a run killed while writing its manifests): it is started again.
std::unique_ptr<TaskStore> open_staging(const Profile& p, const RunOptions& o) {
  const fs::path staging = o.out + ".tasks";
  if (fs::exists(staging)) {
    TaskStore probe(staging);
    const std::string prof = probe.read_manifest("profile.toml"),
                      eng = probe.read_manifest("engine_version");
    const bool checkpoints =
        fs::is_directory(staging / "checkpoints") && !fs::is_empty(staging / "checkpoints");
    if (probe.keys().empty() && !checkpoints) {
      fs::remove_all(staging);
    } else if (prof != p.text || eng != o.engine_version) {
      if (!o.force) refuse(staging.string(), "by another profile or engine (an interrupted run)");
      fs::remove_all(staging);
    }
  }
  auto store = std::make_unique<TaskStore>(staging);
  store->write_manifest("profile.toml", p.text);
  store->write_manifest("engine_version", o.engine_version);
  return store;
}

struct PendingSet {
  std::vector<char> pending;  // [tasks] 1 = to compute in this run
  int total = 0, reused = 0;  // this shard's tasks, and those already done
  double flops = 0;           // the pending tasks' FLOPs (for the ETA)
};

PendingSet find_pending(const Plan& plan, const std::vector<char>& mine,
                        const std::map<std::string, TaskRecord>& prior, const TaskStore& store) {
  const int n = int(plan.tasks.size());
  PendingSet ps;
  ps.pending.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    if (!mine[i]) continue;
    ++ps.total;
    const std::string& k = plan.tasks[i].key;
    if (prior.count(k) || store.has(k)) {
      ++ps.reused;
      continue;
    }
    ps.pending[i] = 1;
    ps.flops += plan.tasks[i].flops;
  }
  // A finished task whose weights were left out of the results file (store_weights = false) is
  // computed again when a pending task needs them (deterministic: the same weights come back).
  // Dependencies precede dependents, so one reverse sweep closes chains (VAE → φ → cells).
  for (int i = n - 1; i >= 0; --i) {
    if (!ps.pending[i]) continue;
    for (int d : plan.tasks[i].deps) {
      const std::string& k = plan.tasks[d].key;
      if (ps.pending[d] || store.has(k)) continue;
      auto it = prior.find(k);
      if (it == prior.end() || it->second.arrays.count("params")) continue;
      ps.pending[d] = 1;
      --ps.reused;
      ps.flops += plan.tasks[d].flops;
    }
  }
  return ps;
}

// Runs the pending tasks (threads, or MPI workers), committing each as it finishes. Returns the
// first failure instead of throwing, so the caller still writes what finished.
std::exception_ptr execute(const Plan& plan, const std::vector<char>& pending, RunContext& ctx,
                           TaskStore& store, CheckpointStore* checkpoints, int threads,
                           int max_task_threads, int mpi_size, Progress& progress, bool quiet) {
  const int n = int(plan.tasks.size());
  // Cached outputs are released when their last pending dependent finishes.
  std::vector<int> users(n, 0);
  for (int i = 0; i < n; ++i)
    if (pending[i])
      for (int d : plan.tasks[i].deps) ++users[d];
  std::mutex users_mu;
  try {
    if (mpi_size > 1) {
      const std::vector<int> ran =
          mpi_dispatch(plan, pending, max_task_threads, [&](int i, const TaskRecord& rec) {
            store.commit(rec);
            progress.task_done(rec.key, plan.tasks[i].flops, rec.num.at("seconds"));
          });
      if (!quiet) {
        std::string per;
        for (size_t w = 1; w < ran.size(); ++w)
          per += (w > 1 ? ", " : "") + std::string("rank ") + std::to_string(w) + " " +
                 std::to_string(ran[w]);
        std::fprintf(stderr, "sirl run: tasks per MPI worker: %s\n", per.c_str());
      }
    } else {
      run_dag(plan, pending, threads, max_task_threads, [&](int i, int cores) {
        Task t = plan.tasks[i];
        t.threads = cores;
        const TaskRecord rec = run_task(t, ctx);
        store.commit(rec);
        if (checkpoints) checkpoints->remove(t.key);  // the task's commit supersedes it
        progress.task_done(t.key, t.flops, rec.num.at("seconds"));
        std::lock_guard lock(users_mu);
        for (int d : t.deps)
          if (--users[d] == 0) ctx.release(plan.tasks[d].key);
      });
    }
  } catch (...) {
    return std::current_exception();
  }
  return nullptr;
}

// This shard's finished records in plan order, weights dropped where the profile says so.
std::vector<TaskRecord> finished_records(const Profile& p, const Plan& plan,
                                         const std::vector<char>& mine,
                                         std::map<std::string, TaskRecord> prior,
                                         const TaskStore& store) {
  std::map<std::string, TaskRecord> all = std::move(prior);
  for (const auto& k : store.keys()) all[k] = store.load(k);
  std::vector<TaskRecord> records;
  for (size_t i = 0; i < plan.tasks.size(); ++i) {
    auto it = all.find(plan.tasks[i].key);
    if (it == all.end() || !mine[i]) continue;
    records.push_back(it->second);
    if (!keeps_weights(p, plan.tasks[i])) records.back().arrays.erase("params");
  }
  return records;
}

RunSummary run_rank0(const Profile& p, const RunOptions& o, int mpi_size) {
  // One writer per output, taken before reading anything of it.
  const FileLock lock(o.out, "sirl run", "wait for it to finish, or choose another --out");
  for (const char* beside : {".tasks", ".partial", ".sum.tmp"}) refuse_symlink(o.out + beside);
  const auto t0 = std::chrono::steady_clock::now();
  const std::string started = now_iso();
  const Plan plan = make_plan(p);
  const std::vector<char> mine = shard_tasks(plan, o.shard_index, o.shard_count);
  // More threads than cores would not run more tasks at once (oneTBB has no more workers),
  // only claim so in the progress line and the file's metadata: say so and use the cores.
  const int cores = usable_cores();
  int threads = mpi_size > 1 ? mpi_size - 1 : o.threads > 0 ? o.threads : cores;
  if (mpi_size <= 1 && threads > cores) {
    std::fprintf(stderr,
                 "sirl run: --threads %d is more than the %d core(s) this process may use; "
                 "running %d threads (results do not depend on it)\n",
                 threads, cores, cores);
    threads = cores;
  }
  const std::string shard =
      o.shard_count > 1 ? std::to_string(o.shard_index) + "/" + std::to_string(o.shard_count) : "";

  // Earlier results: the results file itself, and the staging directory of an interrupted run.
  std::map<std::string, TaskRecord> prior = load_prior(p, o, shard);
  const std::unique_ptr<TaskStore> staged = open_staging(p, o);
  TaskStore& store = *staged;
  const PendingSet ps = find_pending(plan, mine, prior, store);
  RunContext ctx(p, [&](const std::string& key) -> TaskRecord {
    if (store.has(key)) return store.load(key);
    auto it = prior.find(key);
    if (it == prior.end()) throw std::runtime_error("missing result of task " + key);
    return it->second;
  });

  // Training checkpoints (not under MPI: its workers may not share this directory).
  std::unique_ptr<CheckpointStore> checkpoints;
  if (mpi_size <= 1 && o.checkpoint_seconds >= 0) {
    checkpoints =
        std::make_unique<CheckpointStore>(store.dir() / "checkpoints", o.checkpoint_seconds);
    ctx.set_checkpoints([&cs = *checkpoints](const std::string& key) { return cs.for_task(key); });
  }

  fp32_roof_gflops_per_core();  // measured now, on cores the tasks do not use yet
  if (runs_bf16(p)) bf16_roof_gflops_per_core();
  for (size_t i = 0; i < plan.tasks.size(); ++i)
    if (ps.pending[i] && plan.tasks[i].stream_bytes > 0) {
      stream_gbs_per_core();  // likewise, when a task will need its memory roof
      break;
    }
  const int to_run = ps.total - ps.reused;
  if (!o.quiet)
    std::fprintf(stderr, "sirl run: profile %s, %d tasks (%d already done), %d %s → %s\n",
                 p.name.c_str(), ps.total, ps.reused, threads,
                 mpi_size > 1 ? "MPI workers" : "threads", o.out.c_str());
  Progress progress(to_run, ps.flops, o.quiet);
  if (checkpoints) {
    const std::vector<std::string> k = checkpoints->keys();
    progress.set_resumed({k.begin(), k.end()});
  }
  const std::exception_ptr failure =
      execute(plan, ps.pending, ctx, store, checkpoints.get(), threads,
              // Threads: the most cores one task takes; MPI: each worker rank's cores.
              mpi_size > 1             ? std::max(1, o.max_task_threads)
              : o.max_task_threads > 0 ? o.max_task_threads
                                       : threads,
              mpi_size, progress, o.quiet);
  progress.finish();

  // Assemble whatever is finished (a partial file plots with gaps; a rerun completes it).
  const std::vector<TaskRecord> records = finished_records(p, plan, mine, std::move(prior), store);
  RunInfo info;
  info.profile_name = p.name;
  info.profile_text = p.text;
  info.engine_version = o.engine_version;
  info.git_commit = o.git_commit;
  info.host = hostname();
  info.cpu_class = cpu_class();
  info.libraries = library_versions_text();
  info.kernel_paths = kernel_paths();
  // bf16 products run natively or emulated: different bits, so a different class.
  if (runs_bf16(p)) info.cpu_class += std::string(", bf16 ") + bf16_backend();
  info.roof_fp32_gflops = fp32_roof_gflops_per_core();
  if (runs_bf16(p)) info.roof_bf16_gflops = bf16_roof_gflops_per_core();
  if (std::any_of(records.begin(), records.end(),
                  [](const TaskRecord& r) { return r.num.count("stream_bytes") > 0; }))
    info.stream_gbs = stream_gbs_per_core();  // measured before the tasks when any streams
  info.started = started;
  info.finished = now_iso();
  info.shard = shard;
  info.threads = threads;
  info.tasks_total = ps.total;
  info.tasks_done = int64_t(records.size());
  info.complete = info.tasks_done == ps.total;
  info.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<RunDataset> datasets;
  for (const auto& env : p.envs)
    datasets.push_back({&ctx.dataset(env), &ctx.bundle(env, p.axes.at(env).seeds.front())});
  try {
    write_results_file(o.out, info, datasets, records, result_tables(records, info.roofs()));
  } catch (const std::exception&) {
    // A task's failure (a full disk while saving it) is the cause to report; the results file
    // then failed for the same reason. Every committed task stays in the staging folder.
    if (!failure) throw;
  }
  if (failure) std::rethrow_exception(failure);
  crash_point();                // the results file and its checksum are in place
  fs::remove_all(store.dir());  // everything is in the results file now
  RunSummary s;
  s.tasks = ps.total;
  s.reused = ps.reused;
  s.ran = to_run;
  s.seconds = info.wall_seconds;
  return s;
}

}  // namespace

}  // namespace sirl
