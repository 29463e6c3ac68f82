// The task kinds, declared once each: the name a record and /tables/timings carry, one line on
// what it computes, and the function that runs it. The plan (jobs/plan.cpp, jobs/study_tasks.cpp)
// builds tasks of these kinds with their keys, dependencies and cost; run_task dispatches here.
// Adding a kind: a TaskKind value, a runner, a line in task_kinds(), and its planner
// (docs/ARCHITECTURE.md, "Adding a task kind").
#pragma once
#include <vector>

#include "jobs/plan.h"
#include "jobs/task_runner.h"

namespace sirl {

using TaskRunner = void (*)(const Task& t, RunContext& ctx, TaskRecord& r);

struct TaskKindSpec {
  TaskKind kind;
  const char* name;         // "vae", "rep", …: the record's kind
  const char* description;  // one line for `sirl plan` and the docs
  TaskRunner run;           // inputs from ctx, outputs into r (through jobs/task_outputs.h)
};

// Every kind, in TaskKind order.
const std::vector<TaskKindSpec>& task_kinds();
const TaskKindSpec& task_kind(TaskKind k);

}  // namespace sirl
