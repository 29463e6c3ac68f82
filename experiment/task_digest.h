// A task's content digest: its identity in the task store (`sirl run --cache`). Two runs whose
// plans give a task the same digest compute the same bits for it (on one CPU class), whatever
// else differs between their profiles, so the second reuses the first's result.
//
// It hashes (XXH3-128): the numerics version below, the task's kind and key, the fields its
// record describes it with (in_main, best_mode, …), its cost model's stream estimate (recorded),
// what it reads of the profile (its kind's `settings`, compiled with the task:
// experiment/task_config.h) and, in order, the digests of the tasks it reads. The CPU class is not
// in it: the store files a result under digest and class (jobs/run.cpp), and reuse across classes
// is the user's choice.
#pragma once
#include <string>
#include <vector>

#include "experiment/plan.h"
#include "experiment/profile.h"

namespace sirl {

// Raised whenever a change to the engine alters the bits any task computes from the same
// settings (a kernel's order of operations, an RNG stream, a training step): every result
// stored by an engine of another numerics version is then computed again.
inline constexpr int kNumericsVersion = 1;

// One digest per task of the plan, in plan order (32 hex digits each).
std::vector<std::string> task_digests(const Plan& plan);

// The text a task's digest hashes (inputs' digests given): for tests and `sirl plan --why`.
std::string task_digest_text(const Task& t, const std::vector<std::string>& input_digests,
                             const std::vector<std::string>& input_keys);

}  // namespace sirl
