// Runs a plan's pending tasks over a oneTBB arena, honouring dependencies. Ready tasks start in
// order of their "upward rank" (own cost + the costliest chain of tasks waiting on them), so long
// chains start early and the run does not end on one straggler.
#pragma once
#include <functional>
#include <vector>

#include "jobs/plan.h"

namespace sirl {

// pending[i] = task i still has to run (a task whose dependency is not pending counts that
// dependency as done). `work(i)` runs task i on some worker thread; it may throw, in which case
// no new task starts, running ones finish, and the first error is rethrown.
void run_dag(const Plan& plan, const std::vector<char>& pending, int threads,
             const std::function<void(int)>& work);

// The priority used above, exposed for `sirl plan` and tests.
std::vector<double> upward_rank(const Plan& plan);

}  // namespace sirl
