// `sirl plan`, `sirl run`, `sirl export`, `sirl merge`: the batch engine's commands.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "app/cluster_options.h"
#include "app/commands.h"
#include "experiment/cost_model.h"
#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/task_kinds.h"
#include "experiment/task_runner.h"
#include "jobs/cluster_prediction.h"
#include "jobs/estimate.h"
#include "jobs/progress.h"
#include "jobs/run.h"
#include "jobs/schedule_sim.h"
#include "jobs/stop_request.h"
#include "results/file_lock.h"
#include "results/results_file.h"

namespace sirl::app {

Profile load_or_usage(const std::string& name) {
  try {
    return load_profile(name, profile_settings());
  } catch (const ProfileError& e) {
    throw UsageError(e.what());
  }
}

int default_threads() {
  return std::max(1, int(std::thread::hardware_concurrency()));
}

namespace {

std::string format_bytes(uint64_t b) {
  char buf[32];
  if (b >= (uint64_t(1) << 30))
    std::snprintf(buf, sizeof buf, "%.1f GiB", double(b) / double(uint64_t(1) << 30));
  else
    std::snprintf(buf, sizeof buf, "%.0f MiB", double(b) / double(1 << 20));
  return buf;
}

}  // namespace

int run_command(const std::string& profile_name, const std::string& out, int threads, bool force,
                const std::string& shard, bool quiet, bool skip_study, double checkpoint_minutes,
                int max_task_threads) {
  return run_loaded_profile(load_or_usage(profile_name), out, threads, force, shard, quiet,
                            skip_study, checkpoint_minutes, max_task_threads);
}

int run_loaded_profile(Profile p, const std::string& out, int threads, bool force,
                       const std::string& shard, bool quiet, bool skip_study,
                       double checkpoint_minutes, int max_task_threads) {
  if (skip_study) p.study.enabled = false;
  install_stop_handlers();  // SIGTERM / SIGUSR1 / Ctrl-C: checkpoint and stop (exit 75)
  RunOptions o;
  o.out = out;
  o.threads = threads;
  o.max_task_threads = max_task_threads;
  o.force = force;
  o.cache = cache_choice().dir;
  o.any_cpu_class = cache_choice().any_cpu_class;
  o.quiet = quiet;
  o.checkpoint_seconds = checkpoint_minutes * 60;
  o.engine_version = engine_version();
  o.git_commit = git_commit();
  if (!shard.empty()) {
    try {
      parse_shard(shard, o.shard_index, o.shard_count);
    } catch (const std::invalid_argument& e) {
      throw UsageError(e.what());
    }
  }
  const std::filesystem::path parent = std::filesystem::path(out).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
  RunSummary s;
  try {
    s = run_profile(p, o);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  if (s.worker) return 0;
  std::printf("sirl run: %d tasks (%d reused, %d computed%s) in %s → %s\n", s.tasks, s.reused,
              s.ran,
              s.elsewhere ? (", " + std::to_string(s.elsewhere) + " by another run").c_str() : "",
              format_duration(s.seconds).c_str(), out.c_str());
  // The cache is most of what a run leaves on disk: say where it is and how to trim it.
  if (!quiet) {
    const std::filesystem::path cache = cache_dir(o);
    std::printf(
        "task cache: %s (%s; it makes reruns and edited profiles fast; `sirl gc %s %s` keeps "
        "only what this profile needs, `--all` empties it)\n",
        cache.c_str(), format_bytes(folder_bytes(cache)).c_str(), cache.c_str(),
        std::ranges::count(bundled_profiles(), p.name) ? p.name.c_str() : p.path.c_str());
  }
  return 0;
}

void register_run(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand(
      "run",
      "Run a profile's experiment grid into an HDF5 results file.\n"
      "Finished tasks are committed one by one to the task cache (OUT.tasks/, or --cache), filed\n"
      "by what each depends on: rerunning after a crash, or after editing the profile (one more\n"
      "seed, another method, a changed hyper-parameter), computes only the tasks whose inputs\n"
      "changed. `sirl plan PROFILE --cache DIR` says how much is already there.\n"
      "SIGTERM, SIGUSR1 or Ctrl-C: every training in progress saves its state at its next epoch\n"
      "end, the run writes what finished and exits 75; the same command continues (a second\n"
      "Ctrl-C quits at once). Exit codes: 0 done, 1 a task or file failed, 2 usage, 75 stopped.");
  static std::string profile, out, shard;
  static int threads = 0;
  static bool force = false, quiet = false;
  static double checkpoint_minutes = 5;
  static int task_threads = 0;
  cmd->add_option("profile", profile,
                  "Profile: a name in configs/ (" + bundled_profile_names() + ") or a .toml path")
      ->required();
  cmd->add_option("--out", out, "Results file (HDF5)")->required()->check(output_file());
  cmd->add_option("--threads", threads, "Worker threads (default: every core)")
      ->check(CLI::Range(1, 4096));
  cmd->add_option("--shard", shard,
                  "Run only shard i of n (i/n, 0-based), e.g. one Slurm array task; combine the "
                  "shard files with `sirl merge`")
      ->check(CLI::Validator(
          [](std::string& v) {
            return v.empty() ? std::string("must look like i/n, e.g. 0/4") : "";
          },
          "i/n"));
  cmd->add_flag("--force", force,
                "Compute every task again (reusing nothing of the cache or of OUT), and replace "
                "an OUT written for another --shard");
  cmd->add_flag("--quiet", quiet, "No progress output");
  cmd->add_option("--task-threads", task_threads,
                  "The most cores one big task may use when no other task is ready (the tail\n"
                  "of a run) or its chain would outlast the rest of the work spread over the\n"
                  "cores (a critical chain); default: all --threads; 1: one core per task. Under "
                  "MPI: the cores each worker rank's tasks use (default 1), times the idle\n"
                  "workers of its node a big task borrows by the same rules (ranks must not be\n"
                  "bound to single cores for that: mpirun --bind-to none). Results are the same\n"
                  "bits whatever it is")
      ->check(CLI::Range(1, 4096));
  cmd->add_option("--checkpoint-minutes", checkpoint_minutes,
                  "A training running longer saves its state (weights, Adam, random streams, "
                  "curves) at the next epoch's end, to the cache's checkpoints/; a rerun continues "
                  "it to the same result. 0: after every epoch; -1: never")
      ->check(CLI::Range(-1.0, 1e6))
      ->capture_default_str();
  add_set_option(cmd);
  add_cache_options(cmd);
  run = [] {
    return run_command(profile, out, threads, force, shard, quiet, false, checkpoint_minutes,
                       task_threads);
  };
}

ClusterModel cluster_model(const PlanClusterOptions& o) {
  ClusterModel m;
  m.nodes = o.nodes;
  m.cores_per_node = o.cores_per_node > 0 ? o.cores_per_node : default_threads();
  m.mpi = o.mpi || o.nodes > 1;
  m.threads_per_worker = o.threads_per_worker;
  m.max_task_threads = o.task_threads > 0 ? o.task_threads : m.cores_per_node;
  m.serial_fraction = o.serial_fraction;
  m.node_bandwidth = o.node_bandwidth_gbs > 0 ? o.node_bandwidth_gbs * 1e9
                                              : default_node_bandwidth(m.cores_per_node);
  return m;
}

void print_schedule(const Plan& plan, const PlanEstimate& e, const PlanClusterOptions& o) {
  const ClusterModel m = cluster_model(o);
  ClusterPrediction c;
  try {
    c = predict_cluster(plan, e, m, e.pending);
  } catch (const std::invalid_argument& x) {
    throw UsageError(x.what());
  }
  const ScheduleResult& r = c.schedule;
  // Lower bounds on any schedule: every core busy on the work as measured on one core, and the
  // critical path with each of its tasks on the widest a task can be.
  const int widest = m.mpi ? std::max(1, m.cores_per_node - 1) : m.max_task_threads;
  double work = 0;
  for (double s : e.task_seconds) work += s;
  const int task_cores = m.mpi ? r.workers * m.threads_per_worker : m.cores_per_node;
  std::printf(
      "\nschedule (simulated: the engine's ready queue by upward rank over the calibrated "
      "task times)\n");
  if (m.mpi)
    std::printf(
        "  %d node(s) x %d cores, MPI: rank 0 dispatches and commits, %d worker rank(s) x "
        "%d thread(s); a big task alone or on a critical chain borrows idle workers of its "
        "node\n",
        m.nodes, m.cores_per_node, r.workers, m.threads_per_worker);
  else
    std::printf(
        "  1 node x %d cores, threads: a big task takes up to %d cores when nothing else is "
        "ready or its chain outlasts the rest of the work per core\n",
        m.cores_per_node, m.max_task_threads);
  char mpi_start[128] = "";
  if (m.mpi)
    std::snprintf(mpi_start, sizeof mpi_start, ", %.1f s to start MPI, %.0f ms per task to ship it",
                  m.mpi_start_seconds, m.mpi_task_seconds * 1e3);
  std::printf(
      "  assumed: speed-up of k cores on one task k/(1 + %.2f(k-1)); main memory %.0f GB/s "
      "per node; %.0f ms per commit; %.1f ms per task to write the results file%s\n",
      m.serial_fraction, m.node_bandwidth * 1e-9, m.commit_seconds * 1e3,
      m.finish_seconds_per_task * 1e3, mpi_start);
  std::printf(
      "  predicted makespan: %s (%.1f s)   (%.1f s of it outside the tasks: building the data, "
      "writing the results file%s; cores busy %.0f %% of the time; %s lost to memory "
      "bandwidth, summed over tasks)\n",
      format_duration(c.wall_seconds).c_str(), c.wall_seconds, c.outside_seconds,
      m.mpi ? ", starting MPI" : "", 100 * r.utilisation,
      format_duration(r.bandwidth_stall).c_str());
  std::printf(
      "  memory per node: %.0f MiB (its processes' datasets and the largest working sets "
      "that can run there at once)\n",
      c.memory_bytes_per_node / (1024.0 * 1024.0));
  std::printf(
      "  without widening (every task on %s): %s;  lower bounds: the work over every core %s, "
      "the critical path on %d cores %s\n",
      m.mpi ? "its worker rank" : "one core", format_duration(c.narrow.makespan).c_str(),
      format_duration(work / task_cores).c_str(), widest,
      format_duration(r.critical_path_seconds / task_speedup(widest, m.serial_fraction)).c_str());
  std::printf("  critical path: %zu task(s), %s on one core each:\n", r.critical_path.size(),
              format_duration(r.critical_path_seconds).c_str());
  for (int i : r.critical_path)
    std::printf("    %-44s %10s  %.1f GFLOP\n", plan.tasks[size_t(i)].key.c_str(),
                format_duration(e.task_seconds[size_t(i)]).c_str(),
                plan.tasks[size_t(i)].flops * 1e-9);
}

// `sirl plan --tasks`: one line per task (key, kind, GFLOP, MiB, the keys it reads).
void print_task_list(const Plan& plan) {
  for (const Task& t : plan.tasks) {
    std::printf("%s %s %.6g %.6g", t.key.c_str(), t.kind.name(), t.flops * 1e-9,
                t.bytes / (1024.0 * 1024.0));
    for (int d : t.deps) std::printf(" %s", plan.tasks[size_t(d)].key.c_str());
    std::printf("\n");
  }
}

// The profile, its tasks and FLOPs per kind, and what a cache already holds of them (returned;
// `held` is empty without a cache).
CacheHoldings print_plan_summary(const Profile& p, const Plan& plan, const std::string& cache) {
  std::printf("profile %s (%s): %s\n", p.name.c_str(), p.path.c_str(), p.description.c_str());
  std::printf("envs:");
  for (const auto& e : p.envs) std::printf(" %s", e.c_str());
  std::printf("   seeds: %zu   N (FPE): %zu values   N (TPA): %zu   M: %zu\n", p.seeds.size(),
              p.fpe_N.size(), p.tpa.N.size(), p.tpa.M.size());
  std::printf("\n%-16s %8s %14s  %s\n", "kind", "tasks", "GFLOP", "what it computes");
  for (const TaskKindSpec* ks : task_kinds()) {
    if (plan.count(*ks) == 0) continue;
    std::printf("%-16s %8d %14.1f  %s\n", ks->name, plan.count(*ks), plan.flops(*ks) * 1e-9,
                ks->description);
  }
  double total = 0, protocol = 0;
  for (const auto& t : plan.tasks) total += t.flops, protocol += t.protocol_flops;
  std::printf("%-16s %8zu %14.1f\n", "total", plan.tasks.size(), total * 1e-9);
  if (protocol > total * (1 + 1e-9)) {
    // Trainings that end early by rule: the FLOPs above are what they are expected to execute.
    const bool heads_stop =
        std::any_of(p.hyper.begin(), p.hyper.end(),
                    [](const auto& kv) { return tpa_stop_may_end_early(kv.second.tpa_stop); }) ||
        std::any_of(p.tpa_stop_by_method.begin(), p.tpa_stop_by_method.end(),
                    [](const auto& kv) { return tpa_stop_may_end_early(kv.second); });
    const bool phis_stop =
        std::any_of(p.hyper.begin(), p.hyper.end(),
                    [](const auto& kv) { return kv.second.pref_stop == "converged"; }) ||
        std::any_of(p.pref_stop_by_method.begin(), p.pref_stop_by_method.end(),
                    [](const auto& kv) { return kv.second == "converged"; });
    std::printf("%-16s %8s %14.1f  every epoch of every schedule\n", "protocol", "",
                protocol * 1e-9);
    std::vector<std::string> ends{"SIRL's exact skip"};
    if (heads_stop) ends.push_back("reward heads stopped by the profile's tpa.stop rules");
    if (phis_stop) ends.push_back("preference φ stopped by its pref.stop rules");
    std::string expect;
    for (size_t i = 0; i < ends.size(); ++i)
      expect += (i == 0 ? "" : i + 1 == ends.size() ? " and " : ", ") + ends[i];
    std::printf(
        "executes %.3g PFLOP of the protocol's %.3g PFLOP (%.1f %%): the rows above expect"
        " %s (measured stopping epochs: experiment/expected_epochs.cpp)\n",
        total * 1e-15, protocol * 1e-15, 100 * total / protocol, expect.c_str());
  }
  if (cache.empty()) return {};
  const CacheHoldings h = cache_holdings(plan, p, cache);
  std::printf("\ncache %s: %d of %zu tasks already computed on this CPU class (%.1f of %.1f GFLOP)",
              cache.c_str(), h.tasks, plan.tasks.size(), h.flops * 1e-9, total * 1e-9);
  if (h.other_class > 0)
    std::printf("; %d more on another class (%.1f GFLOP; sirl run --any-cpu-class reuses them)",
                h.other_class, h.other_flops * 1e-9);
  std::printf("\n");
  if (h.tasks > 0 && size_t(h.tasks) < plan.tasks.size())
    std::printf("the prediction below is for the %zu tasks left\n",
                plan.tasks.size() - size_t(h.tasks));
  return h;
}

// The calibration's measured rates, the data's build times and the memory estimate.
void print_calibration(const PlanEstimate& e) {
  std::printf("\nmeasured single-thread rates (+ the fixed cost of one call):");
  for (const auto& [k, r] : e.gflops_per_s)
    std::printf("  %s %.1f GFLOP/s + %.0f ms", k.c_str(), r, 1e3 * e.call_seconds.at(k));
  std::printf("\nbuilding the data (one core, outside the tasks):");
  for (const auto& [env, s] : e.dataset_seconds)
    std::printf("  %s: Ξ %.1f s, a seed's queries %.2f s", env.c_str(), s,
                e.bundle_seconds.at(env));
  std::printf("\nmemory estimate: %.1f MiB\n", e.peak_bytes / (1024.0 * 1024.0));
}

// `sirl plan --json`: what print_plan_summary, print_calibration and print_schedule say, as one
// JSON object on stdout.
int print_plan_json(const Profile& p, const Plan& plan, const std::string& cache, int th,
                    const PlanClusterOptions& co, bool cluster) {
  nlohmann::json j;
  j["profile"] = p.name;
  j["path"] = p.path;
  j["description"] = p.description;
  j["environments"] = p.envs;
  double total = 0, protocol = 0;
  for (const auto& t : plan.tasks) total += t.flops, protocol += t.protocol_flops;
  for (const TaskKindSpec* ks : task_kinds())
    if (plan.count(*ks) > 0)
      j["kinds"][ks->name] = {{"tasks", plan.count(*ks)}, {"gflop", plan.flops(*ks) * 1e-9}};
  j["tasks"] = plan.tasks.size();
  j["gflop"] = total * 1e-9;
  j["protocol_gflop"] = protocol * 1e-9;
  std::vector<char> pending(plan.tasks.size(), 1);
  if (!cache.empty()) {
    const CacheHoldings h = cache_holdings(plan, p, cache);
    for (size_t i = 0; i < pending.size(); ++i) pending[i] = !h.held[i];
    j["cache"] = {{"path", cache},
                  {"tasks_held", h.tasks},
                  {"gflop_held", h.flops * 1e-9},
                  {"tasks_other_cpu_class", h.other_class}};
  }
  if (std::find(pending.begin(), pending.end(), 1) == pending.end()) {
    j["prediction"] = nullptr;  // nothing left to compute
  } else {
    refuse_tasks_beyond_memory(plan, pending);
    std::fprintf(stderr, "calibrating on this machine...\n");
    const PlanEstimate e = estimate_plan(plan, p, th, pending);
    PlanClusterOptions here = co;
    if (!cluster) here.cores_per_node = th;
    const ClusterModel m = cluster_model(here);
    ClusterPrediction c;
    try {
      c = predict_cluster(plan, e, m, e.pending);
    } catch (const std::invalid_argument& x) {
      throw UsageError(x.what());
    }
    nlohmann::json path = nlohmann::json::array();
    for (int i : c.schedule.critical_path) path.push_back(plan.tasks[size_t(i)].key);
    j["prediction"] = {{"nodes", m.nodes},
                       {"cores_per_node", m.cores_per_node},
                       {"mpi", m.mpi},
                       {"wall_seconds", c.wall_seconds},
                       {"outside_seconds", c.outside_seconds},
                       {"one_thread_seconds", e.seconds_one_thread},
                       {"cores_busy", c.schedule.utilisation},
                       {"memory_mib_per_node", c.memory_bytes_per_node / (1024.0 * 1024.0)},
                       {"critical_path", path},
                       {"critical_path_seconds", c.schedule.critical_path_seconds},
                       {"calibration_cpu_share", e.cpu_share},
                       {"load_average", e.load_average},
                       {"busy_note", busy_machine_note(e, th)}};
  }
  std::printf("%s\n", j.dump(1, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
  return 0;
}

void register_plan(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand(
      "plan",
      "Show what a profile will run — tasks per kind, FLOPs, memory — and predict its wall time\n"
      "by simulating the engine's scheduler over task times calibrated on this machine (20-40 s "
      "of\n"
      "real training), without running it. With --nodes/--mpi: the same for a cluster of this\n"
      "CPU (MPI ranks pulling tasks from rank 0), with its critical path.");
  static std::string profile;
  static int threads = 0;
  static bool list_tasks = false, resolved = false, keys = false;
  static std::string cache;
  static PlanClusterOptions co;
  cmd->add_option("profile", profile,
                  "Profile: a name in configs/ (" + bundled_profile_names() + ") or a .toml path");
  cmd->add_flag("--keys", keys,
                "Print every profile table's keys instead (type, accepted values, default, what "
                "each sets; [hyper.<env>]'s too) as Markdown: docs/profile-keys.md; no profile "
                "needed");
  cmd->add_option("--threads", threads, "Worker threads to plan for (default: every core)")
      ->check(CLI::Range(1, 4096));
  cmd->add_flag("--tasks", list_tasks,
                "List every task instead (one line each: key, kind, estimated GFLOP and MiB, the\n"
                "keys of the tasks it reads), in the order the plan holds them; no calibration");
  auto* g = cmd->add_option_group("cluster", "Predict a cluster run (these CPUs, other sizes)");
  g->add_option("--nodes", co.nodes, "Nodes (more than one implies --mpi)")
      ->check(CLI::Range(1, 100000));
  g->add_option("--cores-per-node", co.cores_per_node, "Cores per node (default: this machine's)")
      ->check(CLI::Range(1, 4096));
  g->add_flag("--mpi", co.mpi, "Simulate `mpirun ... sirl run` (rank 0 dispatches) on one node");
  g->add_option("--threads-per-worker", co.threads_per_worker,
                "MPI: cores each worker rank's tasks use (sirl run --task-threads under MPI)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  g->add_option("--task-threads", co.task_threads,
                "Threads (one node): the most cores one task may take (default: all, as sirl run)")
      ->check(CLI::Range(1, 4096));
  g->add_option("--node-bandwidth", co.node_bandwidth_gbs,
                "Main-memory bandwidth per node in GB/s that tasks streaming their weights share\n"
                "(default: 15.5 GB/s per core, at most 460)")
      ->check(CLI::Range(0.1, 1e6));
  g->add_option("--serial-fraction", co.serial_fraction,
                "Amdahl serial fraction of one task on several cores (default: the largest of\n"
                "the critical-path tasks', measured from 1 and 2 threads: bench/serial_fraction)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  static bool as_json = false;
  cmd->add_flag("--json", as_json,
                "Print one JSON object instead: tasks and GFLOP per kind, what the cache holds, "
                "the prediction and its critical path (the calibration's messages go to stderr)");
  cmd->add_flag("--resolved", resolved,
                "Print the effective profile instead (after `extends` and --set): the TOML a run "
                "records in its results file");
  cmd->add_option("--cache", cache,
                  "A task cache folder (sirl run --cache; a run's default is OUT.tasks): say how "
                  "many of the plan's tasks it already holds")
      ->type_name("DIR")
      ->check(CLI::ExistingDirectory);
  add_set_option(cmd);
  run = [] {
    if (keys) {
      std::fputs(profile_keys_markdown().c_str(), stdout);
      return 0;
    }
    if (profile.empty()) throw UsageError("sirl plan: a profile is required (or --keys)");
    const Profile p = load_or_usage(profile);
    if (resolved) {
      std::fputs(p.text.c_str(), stdout);
      return 0;
    }
    const Plan plan = make_plan(p);
    if (list_tasks) {
      print_task_list(plan);
      return 0;
    }
    const bool cluster = co.nodes > 1 || co.mpi || co.cores_per_node > 0;
    if (cluster && threads > 0)
      throw UsageError("--threads plans one machine; for a cluster give --cores-per-node");
    const int th = threads > 0 ? threads : default_threads();
    if (as_json) return print_plan_json(p, plan, cache, th, co, cluster);
    const CacheHoldings held = print_plan_summary(p, plan, cache);
    std::vector<char> pending(plan.tasks.size(), 1);
    for (size_t i = 0; i < held.held.size(); ++i) pending[i] = !held.held[i];
    if (!held.held.empty() && size_t(held.tasks) == plan.tasks.size()) {
      std::printf(
          "nothing left to compute: `sirl run %s --cache %s` only writes the results file\n",
          profile.c_str(), cache.c_str());
      return 0;
    }
    std::fflush(stdout);
    // Calibrating trains real tasks: one past this machine's memory is refused, as a run would.
    refuse_tasks_beyond_memory(plan, std::vector<char>(plan.tasks.size(), 1));
    std::fprintf(stderr, "calibrating on this machine...\n");
    const PlanEstimate e = estimate_plan(plan, p, th, pending);
    print_calibration(e);
    if (const std::string busy = busy_machine_note(e, th); !busy.empty())
      std::printf("note: %s\n", busy.c_str());
    PlanClusterOptions here = co;
    if (!cluster) here.cores_per_node = th;
    if (!cluster)
      std::printf("ETA: %s on %d thread(s) (%s on one)\n", format_duration(e.seconds).c_str(), th,
                  format_duration(e.seconds_one_thread).c_str());
    print_schedule(plan, e, here);
    return 0;
  };
}

void register_export(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand("export",
                                 "Write every table of a results file (fpe, tpa, robust_fpe, "
                                 "robust_tpa, study, timings, training, vae_latents, tpa_heads: "
                                 "nine) as <table>.csv into a directory.");
  static std::string file, dir;
  cmd->add_option("file", file, "Results file (HDF5)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--csv", dir, "Directory for the CSV files (one per table)")
      ->required()
      ->check(CLI::Validator(
          [](std::string& v) {
            return v.empty() ? std::string("must name a folder, got an empty path") : std::string();
          },
          "DIR"));
  run = [] {
    const RunInfo info = read_run_info(file);
    if (!info.verified) std::fprintf(stderr, "sirl export: %s\n", unverified_note(file).c_str());
    const auto records = read_results_records(file);
    const ResultTables tables = result_tables(records, info.roofs());
    export_csv(tables, dir);
    std::string names;
    for (const auto& t : tables.tables) names += (names.empty() ? "" : ",") + t.name;
    std::printf("wrote %s/{%s}.csv from %zu task records\n", dir.c_str(), names.c_str(),
                records.size());
    return 0;
  };
}

// Every task record of the shard files, once: files of one profile and engine, a task in two
// files with the same results (timings aside). `wall` is the longest shard's wall time.
// An input no checksum verifies is refused unless `accept_unverified`; its name (and any its own
// merge accepted) goes into `unverified`, which the merged file records.
std::map<std::string, TaskRecord> gather_shard_records(const std::vector<std::string>& inputs,
                                                       const RunInfo& first, double& wall,
                                                       bool accept_unverified,
                                                       std::string& unverified) {
  std::map<std::string, TaskRecord> all;
  for (const auto& in : inputs) {
    const RunInfo info = read_run_info(in);
    if (!info.verified && !accept_unverified)
      throw UsageError(in +
                       " carries no checksum (a file of engine 0.7.0 or older without its .sum), "
                       "so nothing vouches for its values, and merge would write them into a new "
                       "checksummed file: --accept-unverified merges it anyway (the output "
                       "records it in /@unverified_inputs)");
    if (!info.verified) {
      std::fprintf(stderr, "sirl merge: %s\n", unverified_note(in).c_str());
      unverified += in + "\n";
    }
    unverified += info.unverified_inputs;
    if (info.profile_text != first.profile_text)
      throw UsageError(in + " was run under profile '" + info.profile_name + "', " +
                       inputs.front() + " under '" + first.profile_name +
                       "' (or its text differs)");
    if (info.engine_version != first.engine_version)
      throw UsageError(in + " comes from engine " + info.engine_version + ", " + inputs.front() +
                       " from " + first.engine_version);
    wall = std::max(wall, info.wall_seconds);
    for (auto& r : read_results_records(in)) {
      auto it = all.find(r.key);
      if (it != all.end()) {
        TaskRecord a = it->second, b = r;
        a.num.erase("seconds");
        b.num.erase("seconds");
        if (!(a == b)) throw UsageError("task " + r.key + " has different results in two inputs");
        continue;
      }
      all[r.key] = std::move(r);
    }
  }
  return all;
}

void register_merge(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand(
      "merge",
      "Combine shard files (`sirl run --shard i/n`) of one profile into one results file.\n"
      "Refuses files from different profiles or engine versions, and conflicting results; and\n"
      "a merge that lacks some of the plan's tasks unless --partial.");
  static std::string out;
  static std::vector<std::string> inputs;
  static bool force = false, partial = false, accept_unverified = false;
  cmd->add_option("out", out, "Merged results file (a new file: see --force)")
      ->required()
      ->check(output_file());
  cmd->add_option("inputs", inputs, "Shard files")->required()->check(CLI::ExistingFile);
  cmd->add_flag("--force", force, "Replace OUT if it already exists (never one of the inputs)");
  cmd->add_flag("--partial", partial,
                "Write what the inputs hold even when tasks are missing (a shard failed or is "
                "still running): the file lists them (/@missing_tasks), its figures show gaps "
                "and its report marks what rests on them");
  cmd->add_flag("--accept-unverified", accept_unverified,
                "Merge inputs that no checksum verifies (files of engine 0.7.0 or older without "
                "their .sum); the output lists them in /@unverified_inputs");
  run = [] {
    // A forgotten output name makes the first shard the output: never write over an input, and
    // never replace an existing file unless asked. The lock keeps a run writing OUT out.
    namespace fs = std::filesystem;
    std::error_code ec;
    for (const auto& in : inputs)
      if (fs::equivalent(out, in, ec))
        throw UsageError(out +
                         " is also one of the inputs; merge writes a new file: "
                         "sirl merge OUT SHARD...");
    if (fs::exists(out, ec) && !force)
      throw UsageError(out +
                       " already exists; merge writes a new file (sirl merge OUT "
                       "SHARD...): choose another name, or --force to replace it");
    if (const auto dir = fs::path(out).parent_path(); !dir.empty()) fs::create_directories(dir);
    const FileLock lock(out, "sirl merge", "wait for it to finish, or choose another output");
    RunInfo first = read_run_info(inputs.front());
    double wall = 0;
    std::string unverified;
    const std::map<std::string, TaskRecord> all =
        gather_shard_records(inputs, first, wall, accept_unverified, unverified);
    const Profile p = parse_profile(first.profile_text, inputs.front() + "@profile_text");
    const Plan plan = make_plan(p);
    const size_t total = plan.tasks.size();
    if (!partial) {
      std::vector<std::string> missing;
      for (const Task& t : plan.tasks)
        if (!all.count(t.key)) missing.push_back(t.key);
      if (!missing.empty())
        throw UsageError(std::to_string(missing.size()) + " of the plan's " +
                         std::to_string(total) + " tasks are in none of the inputs (e.g. " +
                         missing.front() +
                         "): a shard is missing, failed or still running (`sirl status DIR` "
                         "for a submission); --partial writes what there is");
    }
    RunInfo info = first;
    info.shard = "";
    info.wall_seconds = wall;
    info.unverified_inputs = unverified;
    const size_t written = write_plan_records(out, p, info, all);
    std::printf("merged %zu files: %zu of %zu tasks%s → %s\n", inputs.size(), written, total,
                written == total ? " (complete)" : " (INCOMPLETE)", out.c_str());
    return 0;
  };
}

}  // namespace sirl::app
