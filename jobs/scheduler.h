// Runs a plan's pending tasks over a oneTBB arena, honouring dependencies. Ready tasks start in
// order of their "upward rank" (own cost + the costliest chain of tasks waiting on them), so long
// chains start early and the run does not end on one straggler. A task normally takes one core;
// a big task takes more (task_threads) when nothing else is ready (the tail of a run), or when
// its chain would outlast the rest of the work spread over the cores (a critical chain, such as
// a long VAE → representation → TPA chain on a many-core node). Every kernel gives the same
// bits on any thread count, so widths change timing only.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "experiment/plan.h"

namespace sirl {

// Threads pay off for a task with enough work (FLOPs) in big enough steps: a task whose working
// set is small (GridRobot's φ, 0.7 MiB) runs steps of tens of µs, which a second thread does not
// speed up, while the JacoRobot φ and 20 batched TPA heads gain (docs/kernels.md, "The
// measurements behind the kernels' choices").
inline constexpr double kThreadedTaskFlops = 5e9;
inline constexpr double kThreadedTaskBytes = 4.0 * 1024 * 1024;

// The speed-up the scheduler assumes for a task on k cores when it sizes a critical chain:
// Amdahl's k / (1 + s (k − 1)) with s = 0.25, about what the JacoRobot φ and the 20 batched
// heads gain on 2 cores.
inline constexpr double kAssumedSerialFraction = 0.25;
double task_speedup(int k, double serial_fraction);
// The serial fraction s for which task_speedup(k, s) == speedup (Amdahl inverted), in [0, 1]:
// 1 for k < 2 or a speed-up that is not positive, 0 for a speed-up of k or more.
double serial_fraction_from_speedup(int k, double speedup);
// What the machine model of `sirl plan` (ClusterModel::serial_fraction, --serial-fraction) takes
// by default: the largest serial fraction of the paper's critical-path tasks (JacoRobot VAE, SIRL
// φ, frozen TPA heads), measured by bench/serial_fraction.cpp from 1 and 2 threads: the VAE's
// epochs, the median of seven runs (docs/performance-history.md, "Serial fraction"; 0.64 before
// a model's kernels ran outside any OpenMP region, engine/for_each_model.h). Amdahl's law from 2
// threads is a model of what 64 give, not a measurement of it.
inline constexpr double kMeasuredSerialFraction = 0.47;

// What the scheduler knows when it pops a ready task.
struct CoreOffer {
  int free_cores = 1;          // including the one the task will take
  int total_cores = 1;         // the scheduler's cores
  int max_task_threads = 1;    // the most one task may take
  size_t ready_after = 0;      // tasks still ready after this one
  double chain_flops = 0;      // the task's upward rank: its costliest chain to the end
  double remaining_flops = 0;  // Σ FLOPs of the pending tasks not yet finished (this one too)
  double longest_chain = 0;    // the largest upward rank among ready and running tasks
};

// Cores for the ready task just popped. One, unless the task is big (kThreadedTaskFlops, Bytes)
// and either nothing else is ready (it takes every free core) or its chain is longer than the
// run can end: no sooner than the remaining work spread over the cores, nor than the longest
// chain on max_task_threads cores. Then it takes the fewest cores that bring its chain within
// that bound (at kAssumedSerialFraction), as far as free cores allow. The second bound keeps a
// large cluster from widening every chain that its tiny share per core makes look critical:
// cores given to a task at Amdahl's efficiency are taken from others.
int task_threads(const Task& t, const CoreOffer& o);

// pending[i] = task i still has to run (a task whose dependency is not pending counts that
// dependency as done). `work(i, cores)` runs task i on some worker thread with `cores` threads
// for its kernels; it may throw, in which case no new task starts, running ones finish, and the
// first error is rethrown. At most `threads` cores are in use at once, and the running tasks'
// working sets (Task::bytes) sum to at most `memory_bytes` (0: no limit): a task that does not
// fit beside the running ones waits for them (and the tasks ranked after it wait too, so a big
// task is not starved by small ones); a task alone is always started (`sirl run` refuses one
// larger than the machine before anything runs).
void run_dag(const Plan& plan, const std::vector<char>& pending, int threads, int max_task_threads,
             const std::function<void(int, int)>& work, double memory_bytes = 0);
// One core per task.
void run_dag(const Plan& plan, const std::vector<char>& pending, int threads,
             const std::function<void(int)>& work);

// The cores this process may run threads on (its CPU affinity and cgroup limits, as oneTBB
// counts them): run_dag never gets more working threads than this, whatever it is asked for.
int usable_cores();

// The memory this process may use: the machine's physical memory, or less where a cgroup (v2
// memory.max, v1 memory.limit_in_bytes) limits it.
double usable_memory_bytes();

// oneTBB's version at run time, for provenance.
std::string tbb_version();
}  // namespace sirl
