#include "jobs/estimate.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <functional>
#include <map>
#include <string>

#include "datasets/environments.h"
#include "experiment/calibration.h"
#include "experiment/study_tasks.h"
#include "experiment/task_kinds.h"
#include "experiment/task_settings.h"
#include "jobs/calibration_cache.h"
#include "jobs/schedule_sim.h"
#include "jobs/scheduler.h"

namespace sirl {

namespace {

// This process's CPU time (every thread's), in seconds.
double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// The time f takes on an idle core: the process's CPU time, not the wall clock, so another job
// on the machine does not slow the rates down (the calibration runs on one thread: its CPU time
// is its wall time when it has a core to itself). Wall and CPU time are summed into e for
// cpu_share.
double seconds_of(PlanEstimate& e, const std::function<double()>& f, double* flops) {
  const auto t0 = std::chrono::steady_clock::now();
  const double c0 = process_cpu_seconds();
  *flops = f();
  const double cpu = process_cpu_seconds() - c0;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  e.calibration_wall_seconds += wall;
  e.calibration_cpu_seconds += std::min(cpu, wall);
  return cpu > 0 ? std::min(cpu, wall) : wall;
}
double seconds_of(PlanEstimate& e, const std::function<void()>& f) {
  double none = 0;
  return seconds_of(
      e,
      [&] {
        f();
        return 0.0;
      },
      &none);
}

}  // namespace

namespace {

// The seeds env runs (each builds its own query bundle).
double seed_count(const Profile& p, const std::string& env) {
  const auto axes = p.axes.find(env);
  return axes != p.axes.end() ? double(axes->second.seeds.size()) : 1.0;
}

// Times the making of env's Ξ (from a small one when it is sampled trajectory by trajectory) and
// of one seed's query bundle into e; returns the small Ξ the rates are calibrated on.
Dataset time_setup(const std::string& env, const Profile& p, PlanEstimate& e) {
  // A sampled Ξ is timed on a small one, on one thread as a run builds it (the profile sets it).
  EnvConfig small = p.data;
  constexpr int64_t kSmall = 300;  // enough to time the training code and Ξ's generation rate
  const EnvSpec& spec = env_spec(env);
  if (spec.set_sample) spec.set_sample(small, kSmall, 0);
  Dataset d;
  const double made = seconds_of(e, [&] { d = spec.make(small); });
  // A sampled Ξ costs per trajectory (each one sampled, solved and featurised on its own).
  const double gen =
      spec.set_sample ? made * double(spec.trajectories(p.data)) / double(kSmall) : made;
  QueryBundleConfig full = p.queries;
  full.fpe_trajectories = std::min<int64_t>(full.fpe_trajectories, d.count);
  const double bundle = seconds_of(e, [&] { make_query_bundle(d, full, 1); });
  e.dataset_seconds[env] = gen;
  e.bundle_seconds[env] = bundle;
  e.setup_seconds += gen + seed_count(p, env) * bundle;
  return d;
}

// The single-thread rate (e.gflops_per_s) and fixed cost per call (e.call_seconds) of each rate
// class the plan's tasks in env name (experiment/calibration.h), from short runs of the real
// training code on d.
using RateClasses = std::map<std::string, const RateClass*>;  // by name: a fixed order

// The rate classes the plan's pending tasks in env name.
RateClasses classes_of(const std::string& env, const Plan& plan, const PlanEstimate& e) {
  RateClasses classes;
  for (size_t i = 0; i < plan.tasks.size(); ++i)
    if (const Task& t = plan.tasks[i]; t.env == env && e.pending[i]) {
      const RateClass& c = t.kind.spec().rate(t);
      classes.emplace(c.name, &c);
    }
  return classes;
}

// The hyper-parameters env's classes are calibrated with.
Hyper calibration_hyper(const std::string& env, const Profile& p) {
  return p.hyper.count(env) ? p.hyper.at(env) : study_config(p).hyper;
}

void calibrate_rates(const std::string& env, const Dataset& d, const RateClasses& classes,
                     const Profile& p, PlanEstimate& e) {
  if (classes.empty()) return;
  const Hyper h = calibration_hyper(env, p);
  const CalibrationSample sample = make_calibration_sample(d, p.queries, h, env_spec(env).sampled);
  for (const auto& named : classes) {
    const RateClass* c = named.second;  // not a structured binding: the lambdas below capture it
    const std::string key = env + "/" + named.first;
    if (c->one_length) {
      double f = 0;
      const double s = seconds_of(
          e, [&] { return c->train(sample, 1); }, &f);
      e.gflops_per_s[key] = s > 0 ? f / s * 1e-9 : 1;
      e.call_seconds[key] = 0;
      continue;
    }
    // Each length is timed several times and its fastest time kept: a calibration of a few
    // milliseconds per call (GridRobot) otherwise reads one interruption as a rate off by 2x.
    // At least 3 pairs (2 when a pair takes over a second), more while the class has cost < 0.5 s.
    double f1 = 0, f3 = 0, s1 = 1e300, s3 = 1e300, spent = 0;
    for (int pair = 0; pair < 9; ++pair) {
      const double a = seconds_of(
          e, [&] { return c->train(sample, 1); }, &f1);
      const double b = seconds_of(
          e, [&] { return c->train(sample, 3); }, &f3);
      s1 = std::min(s1, a);
      s3 = std::min(s3, b);
      spent += a + b;
      if (pair + 1 >= (a + b > 1.0 ? 2 : 3) && spent > 0.5) break;
    }
    const double r = s3 > s1 && f3 > f1 ? (f3 - f1) / (s3 - s1) : (s3 > 0 ? f3 / s3 : 1e9);
    e.gflops_per_s[key] = r * 1e-9;
    e.call_seconds[key] = std::max(0.0, s1 - f1 / r);
  }
}

// Each task's time on one core from its kind's rate, the one-thread total, the scheduler's
// makespan on `threads` cores, and the peak memory of the largest tasks running at once.
void time_tasks(const Plan& plan, int threads, PlanEstimate& e) {
  std::vector<double>& secs = e.task_seconds;
  secs.assign(plan.tasks.size(), 0);
  std::vector<double> sizes;
  for (size_t i = 0; i < plan.tasks.size(); ++i) {
    const Task& t = plan.tasks[i];
    const std::string kind = t.kind.spec().rate(t).name;
    double r = 1e9, once = 0;
    if (auto it = e.gflops_per_s.find(t.env + "/" + kind); it != e.gflops_per_s.end())
      r = std::max(it->second, 1e-3) * 1e9;
    if (auto it = e.call_seconds.find(t.env + "/" + kind); it != e.call_seconds.end())
      once = it->second;
    secs[i] = t.flops / r + once;
    if (!e.pending[i]) continue;
    e.seconds_one_thread += secs[i] + ClusterModel{}.commit_seconds;  // as the simulator counts
    sizes.push_back(t.bytes);
  }
  ClusterModel m;
  m.cores_per_node = std::max(1, threads);
  m.max_task_threads = m.cores_per_node;
  e.seconds = simulate_schedule(plan, secs, e.pending, m).makespan;
  std::sort(sizes.rbegin(), sizes.rend());
  for (int k = 0; k < threads && k < int(sizes.size()); ++k) e.peak_bytes += sizes[k];
}

}  // namespace

PlanEstimate estimate_plan(const Plan& plan, const Profile& p, int threads,
                           std::vector<char> pending) {
  PlanEstimate e;
  if (pending.empty()) pending.assign(plan.tasks.size(), 1);
  e.pending = std::move(pending);
  // The grid's environments and the user study's (its tasks run on its own Ξ).
  std::vector<std::string> envs = p.envs;
  if (p.study.enabled && std::find(envs.begin(), envs.end(), p.study.cohort.env) == envs.end())
    envs.push_back(p.study.cohort.env);
  for (const auto& env : envs) {
    const RateClasses classes = classes_of(env, plan, e);
    // What this environment's calibration times (SIRL_CALIBRATION_CACHE keeps it by this text):
    // Ξ's settings, the query counts, the hyper-parameters and the classes.
    std::string what = "calibration env=" + env + "\n" + describe_data(p, env) +
                       describe_queries(p.queries) + describe(calibration_hyper(env, p)) +
                       "classes";
    for (const auto& named : classes) what += " " + named.first;
    what += "\n";
    // Stored: Ξ's and a bundle's seconds, Ξ's bytes, then each class's GFLOP/s and call seconds.
    if (const auto v = load_calibration(what); v && v->size() == 3 + 2 * classes.size()) {
      e.dataset_seconds[env] = (*v)[0];
      e.bundle_seconds[env] = (*v)[1];
      e.setup_seconds += (*v)[0] + seed_count(p, env) * (*v)[1];
      e.data_bytes += (*v)[2];
      size_t k = 3;
      for (const auto& named : classes) {
        e.gflops_per_s[env + "/" + named.first] = (*v)[k++];
        e.call_seconds[env + "/" + named.first] = (*v)[k++];
      }
      continue;
    }
    const Dataset d = time_setup(env, p, e);
    calibrate_rates(env, d, classes, p, e);
    const double bytes = 4.0 * double(d.inputs.size() + d.features.size() * 2);
    e.data_bytes += bytes;
    std::vector<double> v{e.dataset_seconds[env], e.bundle_seconds[env], bytes};
    for (const auto& named : classes) {
      v.push_back(e.gflops_per_s[env + "/" + named.first]);
      v.push_back(e.call_seconds[env + "/" + named.first]);
    }
    save_calibration(what, v);
  }
  e.peak_bytes += e.data_bytes;
  time_tasks(plan, threads, e);
  e.cpu_share =
      e.calibration_wall_seconds > 0 ? e.calibration_cpu_seconds / e.calibration_wall_seconds : 1;
  if (double load[1]; getloadavg(load, 1) == 1) e.load_average = load[0];
  return e;
}

std::string busy_machine_note(const PlanEstimate& e, int threads) {
  const bool busy_core = e.cpu_share < 0.9;
  const bool loaded = e.load_average > 1.25 * double(std::max(1, threads));
  if (!busy_core && !loaded) return "";
  char buf[512];
  std::snprintf(
      buf, sizeof buf,
      "the machine is busy (load average %.1f on %d core(s); the calibration got %.0f %% "
      "of a core): the prediction is for idle cores, and while the load lasts a run "
      "takes longer, about %.1fx if it stays this busy",
      e.load_average, threads, 100 * e.cpu_share,
      std::max(1 / std::max(e.cpu_share, 0.05), e.load_average / double(std::max(1, threads))));
  return buf;
}

}  // namespace sirl
