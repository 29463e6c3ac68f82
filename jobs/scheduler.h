// Runs a plan's pending tasks over a oneTBB arena, honouring dependencies. Ready tasks start in
// order of their "upward rank" (own cost + the costliest chain of tasks waiting on them), so long
// chains start early and the run does not end on one straggler. A task normally takes one core;
// when nothing else is ready (the tail of a run, a lone critical-path chain) a big task takes
// every free core (task_threads), since every kernel gives the same bits on any thread count.
#pragma once
#include <functional>
#include <vector>

#include "jobs/plan.h"

namespace sirl {

// Threads pay off for a task with enough work (FLOPs) in big enough steps: a task whose working
// set is small (GridRobot's φ, 0.7 MiB) runs steps of tens of µs, which a second thread does not
// speed up (bench: 0.25–0.49 ms per step on 2 threads against 0.25–0.28 on 1), while the
// JacoRobot φ (1.5× on 2 threads) and 20 batched TPA heads (1.7×) gain.
inline constexpr double kThreadedTaskFlops = 5e9;
inline constexpr double kThreadedTaskBytes = 4.0 * 1024 * 1024;

// Cores for the ready task just popped, given the free cores (including the one it will take),
// how many tasks are still ready after it, and the most one task may take.
int task_threads(const Task& t, int free_cores, size_t ready_after, int max_task_threads);

// pending[i] = task i still has to run (a task whose dependency is not pending counts that
// dependency as done). `work(i, cores)` runs task i on some worker thread with `cores` threads
// for its kernels; it may throw, in which case no new task starts, running ones finish, and the
// first error is rethrown. At most `threads` cores are in use at once.
void run_dag(const Plan& plan, const std::vector<char>& pending, int threads, int max_task_threads,
             const std::function<void(int, int)>& work);
// One core per task.
void run_dag(const Plan& plan, const std::vector<char>& pending, int threads,
             const std::function<void(int)>& work);

// The priority used above, exposed for `sirl plan` and tests.
std::vector<double> upward_rank(const Plan& plan);

}  // namespace sirl
