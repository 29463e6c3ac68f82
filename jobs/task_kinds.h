// The task kinds, each declared once with everything about it: its name and what it computes,
// its key scheme, the tasks it reads, its cost model, its runner, what its record describes, and
// the results table it contributes. The planners (jobs/plan.cpp, jobs/study_tasks.cpp) only say
// which tasks a profile asks for, with their fields set; add_task derives the rest from here.
// Adding a kind: a TaskKind value, its functions, one line in task_kinds() (docs/ARCHITECTURE.md,
// "Adding a task kind").
#pragma once
#include <string>
#include <vector>

#include "jobs/plan.h"
#include "jobs/task_runner.h"
#include "results/results_file.h"

namespace sirl {

struct TaskKindSpec {
  TaskKind kind;
  const char* name;         // "vae", "rep", …: the record's kind, /tables/timings' kind column
  const char* description;  // one line for `sirl plan` and the docs
  // The task's key from its fields: its identity in the plan, its commit and its RNG streams.
  std::string (*key)(const Task& t);
  // The tasks whose outputs it reads, fields set (add_task adds them first and keys them).
  std::vector<Task> (*inputs)(const Task& t, const Profile& p);
  // What it reads of the profile besides its inputs' outputs, as canonical text
  // (jobs/task_settings.h): with its key and its inputs' digests, its content digest
  // (jobs/task_digest.h). Everything its record depends on must be here: a setting left out lets
  // a run reuse a result computed under another value.
  std::string (*settings)(const Task& t, const Profile& p);
  // Sets t.flops and t.bytes (estimates for `sirl plan` and the scheduler's memory bound).
  void (*cost)(Task& t, const Profile& p);
  // Which measured single-thread rate `sirl plan` times the task with (jobs/estimate.cpp).
  const char* (*rate)(const Task& t);
  // The shard group: tasks of one group run in the same shard ("" = every shard that needs it).
  std::string (*shard_group)(const Task& t);
  bool stores_weights;  // the results file may keep its weights (the environment's store_weights)
  // The task's own fields in its record (what its table's columns read besides its results).
  void (*describe)(const Task& t, TaskRecord& r);
  // Computes the task: inputs from ctx, outputs into r (through jobs/task_outputs.h, the one path
  // by which fresh and resumed runs hand results to later tasks).
  void (*run)(const Task& t, RunContext& ctx, TaskRecord& r);
  // The results table it contributes (/tables/<name>, <name>.csv); no name: none.
  CellTableSpec table;
};

// Every kind, in TaskKind order.
const std::vector<TaskKindSpec>& task_kinds();
const TaskKindSpec& task_kind(TaskKind k);

// Adds t to the plan unless a task with its key is there (a task shared by several cells appears
// once), after the inputs it reads; sets its key, deps and cost from its kind. Returns its index.
int add_task(Plan& plan, const Profile& p, Task t);

// The record fields every task carries: its environment and seed (a kind's `describe` for tasks
// with nothing more to say, and the start of every other kind's).
void describe_env_and_seed(const Task& t, TaskRecord& r);

// The results file's tables from its records: every kind's table, then the cross-kind ones, with
// the roofs the run measured (results_file.h: build_tables).
ResultTables result_tables(const std::vector<TaskRecord>& records, const Roofs& roofs = {});

}  // namespace sirl
