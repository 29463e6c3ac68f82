#include "jobs/run.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>

#include "experiment/task_digest.h"
#include "experiment/task_kinds.h"
#include "experiment/task_runner.h"
#include "jobs/mpi_run.h"
#include "jobs/progress.h"
#include "jobs/provenance.h"
#include "jobs/scheduler.h"
#include "jobs/stop_request.h"
#include "jobs/task_cache.h"
#include "jobs/task_checkpoints.h"
#include "kernels/gemm_bf16.h"
#include "kernels/rng.h"
#include "probes/cpu_class.h"
#include "probes/roofline.h"
#include "results/durable.h"
#include "results/file_lock.h"
#include "results/h5.h"
#include "results/results_file.h"
#include "results/task_store.h"

namespace sirl {

namespace fs = std::filesystem;

namespace {

// The FLOPs a task's record says it executed (its timings row's); -1 when it does not say.
double executed_flops(const TaskRecord& r) {
  const auto it = r.num.find("flops");
  return it == r.num.end() ? -1 : it->second;
}

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
  return t.kind.spec().stores_weights && it != p.axes.end() && it->second.store_weights;
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
  info.missing_tasks.clear();
  for (const auto& t : plan.tasks)
    if (!all.count(t.key)) info.missing_tasks += t.key + "\n";
  info.hyper_points = hyper_points_text(p);
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
        text.find('/', slash + 1) != std::string::npos ||
        // One spelling per shard ("00/2" is "0/2": two runs must not file one shard twice).
        (text[0] == '0' && slash > 1) || (text[slash + 1] == '0' && slash + 2 < text.size()))
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
    const std::string g = plan.tasks[i].kind.spec().shard_group(plan.tasks[i]);
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
    // A worker: inputs of its tasks come from the cache rank 0 commits to (shared file system),
    // the one filed under this worker's CPU class first, or from the results file of an earlier
    // run.
    const Plan plan = make_plan(p);
    const std::vector<std::string> digests = task_digests(plan);
    const fs::path cache = cache_dir(o);
    RunContext ctx(p, [&](const std::string& key) -> TaskRecord {
      const int i = plan.index.at(key);
      const std::string& digest = digests[size_t(i)];
      const std::string own = TaskCache::id(digest, task_cpu_class(plan.tasks[size_t(i)]));
      try {
        return TaskStore::load_from(cache, own, key);
      } catch (const H5Error&) {
      }
      for (const std::string& id : TaskStore::ids_in(cache))
        if (id.starts_with(digest + "-")) return TaskStore::load_from(cache, id, key);
      H5File f = H5File::open_read(o.out);
      return read_record(f, "/runs/" + key);
    });
    // Trainings checkpoint into the cache rank 0 owns (the shared output folder), by digest:
    // a rerun's worker, whichever rank it is, continues them.
    CheckpointStore checkpoints(cache / "checkpoints", o.checkpoint_seconds);
    ctx.set_checkpoints([&](const std::string& key) {
      return checkpoints.for_task(digests[size_t(plan.index.at(key))], key);
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

ResumeDecision resume_decision(const RunInfo& existing, const std::string& shard, bool force) {
  auto part = [](const std::string& s) { return s.empty() ? "the whole run" : "shard " + s; };
  ResumeDecision d;
  if (!force && existing.shard != shard) {
    // writing another part would replace this file's tasks with that part's
    d.refusal = "with " + part(existing.shard) + " (" + std::to_string(existing.tasks_done) +
                " tasks), and this run is " + part(shard);
    return d;
  }
  d.reuse = !force && existing.verified;
  return d;
}

CacheHoldings cache_holdings(const Plan& plan, const Profile& p, const fs::path& dir) {
  const std::vector<std::string> ids = TaskStore::ids_in(dir);
  const std::set<std::string> have(ids.begin(), ids.end());
  std::set<std::string> digests;  // of any class
  for (const std::string& id : ids) digests.insert(id.substr(0, id.find('-')));
  const std::vector<std::string> dig = task_digests(plan);
  CacheHoldings h;
  h.held.assign(plan.tasks.size(), 0);
  for (size_t i = 0; i < plan.tasks.size(); ++i) {
    const Task& t = plan.tasks[i];
    if (have.count(TaskCache::id(dig[i], task_cpu_class(t)))) {
      h.held[i] = 1;
      ++h.tasks;
      h.flops += t.flops;
    } else if (digests.count(dig[i])) {
      ++h.other_class;
      h.other_flops += t.flops;
    }
  }
  return h;
}

fs::path cache_dir(const RunOptions& o) {
  return o.cache.empty() ? fs::path(o.out + ".tasks") : fs::path(o.cache);
}

namespace {

[[noreturn]] void refuse(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + " was written " + what +
                              "; rerun with --force to discard it, or choose another --out");
}

// Records of an existing results file that this plan can reuse: those whose task digest and
// CPU class match (files of engine 0.10.0 on). A file of another part of the grid is refused
// unless --force (which reuses nothing).
std::map<std::string, TaskRecord> load_prior(const Profile& p, const RunOptions& o,
                                             const std::string& shard, const Plan& plan,
                                             const std::vector<std::string>& digests) {
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
  const ResumeDecision d = resume_decision(info, shard, o.force);
  if (!d.refusal.empty()) refuse(o.out, d.refusal);
  // Records are reused only from a file a checksum verified: the new file's checksum would
  // otherwise vouch for bytes nobody checked.
  if (!info.verified)
    std::fprintf(stderr, "sirl run: %s; its tasks are not reused\n",
                 unverified_note(o.out).c_str());
  if (!d.reuse) return prior;
  for (auto& r : read_results_records(o.out)) {
    const auto it = plan.index.find(r.key);
    if (it == plan.index.end()) continue;
    const Task& t = plan.tasks[size_t(it->second)];
    const auto dig = r.text.find("task_digest"), cls = r.text.find("cpu_class");
    if (dig == r.text.end() || dig->second != digests[size_t(it->second)] || cls == r.text.end() ||
        (!o.any_cpu_class && cls->second != task_cpu_class(t)))
      continue;
    prior[r.key] = std::move(r);
  }
  return prior;
}

struct PendingSet {
  std::vector<char> pending;             // [tasks] 1 = to compute in this run
  int total = 0, reused = 0;             // this shard's tasks, and those already done
  double flops = 0;                      // the pending tasks' FLOPs (for the ETA)
  std::vector<std::string> other_class;  // keys of reused results of another CPU class
};

// Where each finished task of the plan is read from: its id in the cache ("" = the results
// file's record, or not finished). Written as tasks finish, from several threads.
class Sources {
 public:
  explicit Sources(size_t n) : id_(n) {}
  void set(size_t i, std::string id) {
    std::lock_guard lock(mu_);
    id_[i] = std::move(id);
  }
  std::string get(size_t i) const {
    std::lock_guard lock(mu_);
    return id_[i];
  }

 private:
  mutable std::mutex mu_;
  std::vector<std::string> id_;
};

PendingSet find_pending(const Profile& p, const Plan& plan, const std::vector<char>& mine,
                        const std::vector<std::string>& digests,
                        const std::map<std::string, TaskRecord>& prior, TaskCache& cache,
                        Sources& sources, const RunOptions& o) {
  const int n = int(plan.tasks.size());
  PendingSet ps;
  ps.pending.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    if (!mine[i]) continue;
    ++ps.total;
    const Task& t = plan.tasks[i];
    const std::string cls = task_cpu_class(t);
    if (!o.force) {
      if (const std::string id = cache.find(digests[i], cls, o.any_cpu_class); !id.empty()) {
        // Checked before anything reads it: a damaged file is removed and the task computed.
        const std::string bad = cache.store().verify(id, t.key);
        if (bad.empty()) {
          sources.set(size_t(i), id);
          if (id != TaskCache::id(digests[i], cls)) ps.other_class.push_back(t.key);
          ++ps.reused;
          continue;
        }
        std::fprintf(stderr, "sirl run: %s; it is computed again\n", bad.c_str());
      }
      if (prior.count(t.key)) {
        ++ps.reused;
        continue;
      }
    }
    ps.pending[i] = 1;
    ps.flops += t.flops;
  }
  // A finished task whose weights were left out of the results file (store_weights = false) is
  // computed again when a pending task needs them (deterministic: the same weights come back).
  // Dependencies precede dependents, so one reverse sweep closes chains (VAE → φ → cells).
  for (int i = n - 1; i >= 0; --i) {
    if (!ps.pending[i]) continue;
    for (int d : plan.tasks[i].deps) {
      const std::string& k = plan.tasks[d].key;
      if (ps.pending[d] || !sources.get(size_t(d)).empty()) continue;
      auto it = prior.find(k);
      if (it == prior.end() || it->second.arrays.count("params")) continue;
      ps.pending[d] = 1;
      --ps.reused;
      ps.flops += plan.tasks[d].flops;
    }
  }
  return ps;
}

// Runs the pending tasks (threads, or MPI workers), committing each to the cache as it
// finishes. A task another run is computing is waited for and read, not computed twice.
struct PlanExecution {
  const Profile& p;
  const Plan& plan;
  const std::vector<std::string>& digests;
  const std::vector<char>& pending;
  RunContext& ctx;
  TaskCache& cache;
  Sources& sources;
  CheckpointStore* checkpoints;
  const RunOptions& o;
  Progress& progress;
  std::atomic<int> elsewhere{0};  // tasks another run computed while this one waited

  // Files a finished record under its digest and the class that computed it.
  void commit(size_t i, TaskRecord& rec) {
    rec.text["task_digest"] = digests[i];
    const std::string id = TaskCache::id(digests[i], rec.text.at("cpu_class"));
    cache.store().commit(rec, id);
    sources.set(i, id);
  }

  void run_one(int i, int cores) {
    Task t = plan.tasks[size_t(i)];
    // After a stop request no task starts; the scheduler then waits for those running.
    if (stop_requested()) throw StopRequested("not started: " + t.key);
    t.threads = cores;
    const TaskCache::Claim claim = cache.claim(digests[size_t(i)], [&] {
      if (!o.quiet)
        std::fprintf(stderr, "sirl run: another run is computing %s; waiting for its result\n",
                     t.key.c_str());
    });
    const std::string done =
        o.force ? "" : cache.find(digests[size_t(i)], task_cpu_class(t), o.any_cpu_class);
    if (!done.empty()) {  // committed by another run while this one waited
      sources.set(size_t(i), done);
      ++elsewhere;
      progress.done_elsewhere(t.key, t.flops);
      return;
    }
    TaskRecord rec = run_task(t, ctx);
    commit(size_t(i), rec);
    if (checkpoints) checkpoints->remove(digests[size_t(i)]);  // the commit supersedes it
    progress.task_done(t.key, t.flops, rec.num.at("seconds"), executed_flops(rec));
  }

  // Returns the first failure instead of throwing, so the caller still writes what finished.
  std::exception_ptr run(int threads, int max_task_threads, int mpi_size) {
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
            mpi_dispatch(plan, pending, max_task_threads, [&](int i, const TaskRecord& r) {
              TaskRecord rec = r;
              commit(size_t(i), rec);
              if (checkpoints) checkpoints->remove(digests[size_t(i)]);
              progress.task_done(rec.key, plan.tasks[i].flops, rec.num.at("seconds"),
                                 executed_flops(rec));
            });
        if (!o.quiet) {
          std::string per;
          for (size_t w = 1; w < ran.size(); ++w)
            per += (w > 1 ? ", " : "") + std::string("rank ") + std::to_string(w) + " " +
                   std::to_string(ran[w]);
          std::fprintf(stderr, "sirl run: tasks per MPI worker: %s\n", per.c_str());
        }
      } else {
        run_dag(
            plan, pending, threads, max_task_threads,
            [&](int i, int cores) {
              run_one(i, cores);
              std::lock_guard lock(users_mu);
              for (int d : plan.tasks[size_t(i)].deps)
                if (--users[d] == 0) ctx.release(plan.tasks[d].key);
            },
            usable_memory_bytes());
      }
    } catch (...) {
      return std::current_exception();
    }
    return nullptr;
  }
};

// This shard's finished records in plan order, weights dropped where the profile says so.
std::vector<TaskRecord> finished_records(const Profile& p, const Plan& plan,
                                         const std::vector<char>& mine,
                                         const std::map<std::string, TaskRecord>& prior,
                                         TaskCache& cache, const Sources& sources) {
  std::vector<TaskRecord> records;
  for (size_t i = 0; i < plan.tasks.size(); ++i) {
    if (!mine[i]) continue;
    const std::string& key = plan.tasks[i].key;
    if (const std::string id = sources.get(i); !id.empty())
      records.push_back(cache.store().load(id, key));
    else if (auto it = prior.find(key); it != prior.end())
      records.push_back(it->second);
    else
      continue;
    if (!keeps_weights(p, plan.tasks[i])) records.back().arrays.erase("params");
  }
  return records;
}

}  // namespace

// A task whose working set (its cost model's estimate: weights, gradient, Adam's moments, a
// batch's activations) exceeds the memory this process may use (the machine's, or its cgroup's
// limit) would fail deep inside its training, or take the machine down with it: refused before
// anything runs, naming the task. (Tasks that fit alone but not together are the scheduler's:
// run_dag starts a task only beside running ones it fits with.)
void refuse_tasks_beyond_memory(const Plan& plan, const std::vector<char>& mine) {
  const double ram = usable_memory_bytes();
  for (size_t i = 0; i < plan.tasks.size(); ++i)
    if (mine[i] && plan.tasks[i].bytes > ram)
      throw std::runtime_error(
          "task " + plan.tasks[i].key + " needs " +
          std::to_string(int64_t(plan.tasks[i].bytes / (1 << 30))) +
          " GiB to train, this process may use " + std::to_string(int64_t(ram / (1 << 30))) +
          " GiB (`sirl plan PROFILE --tasks` lists every task's working set in MiB)");
}

namespace {

// The worker threads (MPI: worker ranks) a run uses. More threads than cores would not run more
// tasks at once (oneTBB has no more workers), only claim so in the progress line and the file's
// metadata: say so and use the cores.
int run_threads(const RunOptions& o, int mpi_size) {
  if (mpi_size > 1) return mpi_size - 1;
  const int cores = usable_cores();
  const int threads = o.threads > 0 ? o.threads : cores;
  if (threads <= cores) return threads;
  std::fprintf(stderr,
               "sirl run: --threads %d is more than the %d core(s) this process may use; "
               "running %d threads (results do not depend on it)\n",
               threads, cores, cores);
  return cores;
}

// The checkpoint store in the cache, handed to ctx's trainings by task digest. A checkpoint of a
// task already committed (a crash between its commit and the checkpoint's removal) is never
// needed again: removed.
std::unique_ptr<CheckpointStore> open_checkpoints(const TaskCache& cache, const RunOptions& o,
                                                  const Plan& plan,
                                                  const std::vector<std::string>& digests,
                                                  const std::vector<char>& mine,
                                                  const std::vector<char>& pending,
                                                  RunContext& ctx) {
  auto checkpoints =
      std::make_unique<CheckpointStore>(cache.dir() / "checkpoints", o.checkpoint_seconds);
  ctx.set_checkpoints([&cs = *checkpoints, &plan, &digests](const std::string& key) {
    return cs.for_task(digests[size_t(plan.index.at(key))], key);
  });
  for (size_t i = 0; i < plan.tasks.size(); ++i)
    if (mine[i] && !pending[i]) checkpoints->remove(digests[i]);
  return checkpoints;
}

// The keys of the plan's tasks that continue a checkpoint (their work so far is not this
// process's: Progress keeps them out of its rate).
std::set<std::string> resumed_keys(const CheckpointStore& checkpoints, const Plan& plan,
                                   const std::vector<std::string>& digests) {
  std::map<std::string, std::string> key_of;  // digest → key, for this plan's tasks
  for (size_t i = 0; i < plan.tasks.size(); ++i) key_of[digests[i]] = plan.tasks[i].key;
  std::set<std::string> resumed;
  for (const std::string& d : checkpoints.keys())
    if (auto it = key_of.find(d); it != key_of.end()) resumed.insert(it->second);
  return resumed;
}

// Measures the roofs the results file records (probes/roofline.h keeps them per process):
// before the tasks, on cores they do not use yet; the memory roof only when a task streams.
void measure_roofs(const Profile& p, const Plan& plan, const std::vector<char>& pending) {
  fp32_roof_gflops_per_core();
  if (runs_bf16(p)) bf16_roof_gflops_per_core();
  for (size_t i = 0; i < plan.tasks.size(); ++i)
    if (pending[i] && plan.tasks[i].stream_bytes > 0) {
      stream_gbs_per_core();
      break;
    }
}

void announce_run(const Profile& p, const RunOptions& o, const PendingSet& ps, int threads,
                  int mpi_size) {
  std::fprintf(stderr, "sirl run: profile %s, %d tasks (%d already done), %d %s → %s\n",
               p.name.c_str(), ps.total, ps.reused, threads,
               mpi_size > 1 ? "MPI workers" : "threads", o.out.c_str());
  if (!ps.other_class.empty())
    std::fprintf(stderr,
                 "sirl run: %zu reused tasks were computed on another CPU class "
                 "(--any-cpu-class; /tables/timings' cpu_class says which), e.g. %s\n",
                 ps.other_class.size(), ps.other_class.front().c_str());
}

// What the results file says about the run besides its tasks and times: the profile, the engine
// and the machine (CPU class, libraries, kernel paths, the roofs measured before the tasks).
RunInfo run_info(const Profile& p, const RunOptions& o, const std::vector<TaskRecord>& records) {
  RunInfo info;
  info.profile_name = p.name;
  info.profile_text = p.text;
  info.engine_version = o.engine_version;
  info.git_commit = o.git_commit;
  info.host = hostname();
  info.cpu_class = cpu_class();
  info.libraries = library_versions_text();
  info.kernel_paths = kernel_paths();
  info.hyper_points = hyper_points_text(p);
  // bf16 products run natively or emulated: different bits, so a different class.
  if (runs_bf16(p)) info.cpu_class += std::string(", bf16 ") + bf16_backend();
  info.roof_fp32_gflops = fp32_roof_gflops_per_core();
  if (runs_bf16(p)) info.roof_bf16_gflops = bf16_roof_gflops_per_core();
  if (std::any_of(records.begin(), records.end(),
                  [](const TaskRecord& r) { return r.num.count("stream_bytes") > 0; }))
    info.stream_gbs = stream_gbs_per_core();  // measured before the tasks when any streams
  return info;
}

// Files this shard's tasks under the run's needs in the cache: sirl gc keeps them while it lives.
void register_needs(TaskCache& cache, const std::vector<std::string>& digests,
                    const std::vector<char>& mine) {
  std::vector<std::string> needed;
  for (size_t i = 0; i < digests.size(); ++i)
    if (mine[i]) needed.push_back(digests[i]);
  cache.register_needs(needed);
}

// Each environment's Ξ and its first seed's queries, as the results file keeps them.
std::vector<RunDataset> run_datasets(const Profile& p, RunContext& ctx) {
  std::vector<RunDataset> datasets;
  for (const auto& env : p.envs)
    datasets.push_back({&ctx.dataset(env), &ctx.bundle(env, p.axes.at(env).seeds.front())});
  return datasets;
}

RunSummary run_rank0(const Profile& p, const RunOptions& o, int mpi_size) {
  // One writer per output, taken before reading anything of it.
  const FileLock lock(o.out, "sirl run", "wait for it to finish, or choose another --out");
  for (const char* beside : {".tasks", ".partial", ".sum.tmp"}) refuse_symlink(o.out + beside);
  refuse_symlink(cache_dir(o).string());
  const auto t0 = std::chrono::steady_clock::now();
  const std::string started = now_iso();
  const Plan plan = make_plan(p);
  const std::vector<std::string> digests = task_digests(plan);
  const std::vector<char> mine = shard_tasks(plan, o.shard_index, o.shard_count);
  refuse_tasks_beyond_memory(plan, mine);
  const int threads = run_threads(o, mpi_size);
  const std::string shard =
      o.shard_count > 1 ? std::to_string(o.shard_index) + "/" + std::to_string(o.shard_count) : "";

  // Earlier results: the task cache, and the records of the results file being replaced.
  const std::map<std::string, TaskRecord> prior = load_prior(p, o, shard, plan, digests);
  TaskCache cache(cache_dir(o));
  register_needs(cache, digests, mine);
  Sources sources(plan.tasks.size());
  const PendingSet ps = find_pending(p, plan, mine, digests, prior, cache, sources, o);
  RunContext ctx(p, [&](const std::string& key) -> TaskRecord {
    const size_t i = size_t(plan.index.at(key));
    if (const std::string id = sources.get(i); !id.empty()) return cache.store().load(id, key);
    auto it = prior.find(key);
    if (it == prior.end()) throw std::runtime_error("missing result of task " + key);
    return it->second;
  });

  // Training checkpoints, by task digest (under MPI the workers save them into this cache too).
  std::unique_ptr<CheckpointStore> checkpoints;
  if (o.checkpoint_seconds >= 0)
    checkpoints = open_checkpoints(cache, o, plan, digests, mine, ps.pending, ctx);

  measure_roofs(p, plan, ps.pending);  // now, on cores the tasks do not use yet
  const int to_run = ps.total - ps.reused;
  if (!o.quiet) announce_run(p, o, ps, threads, mpi_size);
  Progress progress(to_run, ps.flops, o.quiet);
  if (checkpoints) {
    progress.set_resumed(resumed_keys(*checkpoints, plan, digests));
    checkpoints->on_resume(
        [&progress](const std::string& key, double flops) { progress.resumed_from(key, flops); });
  }
  PlanExecution exec{p,     plan,    digests,           ps.pending, ctx,
                     cache, sources, checkpoints.get(), o,          progress};
  const std::exception_ptr failure =
      exec.run(threads,
               // Threads: the most cores one task takes; MPI: each worker rank's cores.
               mpi_size > 1             ? std::max(1, o.max_task_threads)
               : o.max_task_threads > 0 ? o.max_task_threads
                                        : threads,
               mpi_size);
  progress.finish();
  if (checkpoints) checkpoints->on_resume(nullptr);  // progress ends here; the store lives on

  // Assemble whatever is finished (a partial file plots with gaps; a rerun completes it).
  const std::vector<TaskRecord> records = finished_records(p, plan, mine, prior, cache, sources);
  RunInfo info = run_info(p, o, records);
  info.started = started;
  info.finished = now_iso();
  info.shard = shard;
  info.threads = threads;
  info.tasks_total = ps.total;
  info.tasks_done = int64_t(records.size());
  info.complete = info.tasks_done == ps.total;
  info.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  try {
    write_results_file(o.out, info, run_datasets(p, ctx), records,
                       result_tables(records, info.roofs()));
  } catch (const std::exception&) {
    // A task's failure (a full disk while saving it) is the cause to report; the results file
    // then failed for the same reason. Every committed task stays in the cache.
    if (!failure) throw;
  }
  if (failure) std::rethrow_exception(failure);
  crash_point();  // the results file and its checksum are in place
  RunSummary s;
  s.tasks = ps.total;
  s.reused = ps.reused;
  s.elsewhere = exec.elsewhere;
  s.ran = to_run - s.elsewhere;
  s.seconds = info.wall_seconds;
  return s;
}

}  // namespace

}  // namespace sirl
