// The task kinds, each declared once with everything about it: its name and what it computes,
// its key scheme, the tasks it reads, its cost model, its runner, what its record describes, and
// the results table it contributes. A kind's declaration lives in its own file and registers
// itself there (TaskKindRegistration); nothing else lists the kinds. The planners
// (experiment/plan.cpp, experiment/study_tasks.cpp) only say which tasks a profile asks for, with
// their fields set; add_task derives the rest from here. Adding a kind: docs/ARCHITECTURE.md,
// "Adding a task kind".
#pragma once
#include <string>
#include <vector>

#include "experiment/task.h"
#include "experiment/task_runner.h"
#include "results/results_file.h"

namespace sirl {

struct RateClass;  // experiment/calibration.h

struct TaskKindSpec {
  const char* name;         // "vae", "rep", …: the record's kind, /tables/timings' kind column
  const char* description;  // one line for `sirl plan` and the docs
  // The task's key from its fields: its identity in the plan, its commit and its RNG streams.
  std::string (*key)(const Task& t);
  // The tasks whose outputs it reads, fields set (add_task adds them first and keys them).
  std::vector<Task> (*inputs)(const Task& t, const Profile& p);
  // What it reads of the profile besides its inputs' outputs, as canonical text
  // (experiment/task_settings.h): with its key and its inputs' digests, its content digest
  // (experiment/task_digest.h). Everything its record depends on must be here: a setting left out
  // lets a run reuse a result computed under another value.
  std::string (*settings)(const Task& t, const Profile& p);
  // Sets t.flops and t.bytes (estimates for `sirl plan` and the scheduler's memory bound).
  void (*cost)(Task& t, const Profile& p);
  // The rate class `sirl plan` times the task with (experiment/calibration.h), declared beside
  // the kind: the training its FLOPs are spent in.
  const RateClass& (*rate)(const Task& t);
  // The shard group: tasks of one group run in the same shard ("" = every shard that needs it).
  std::string (*shard_group)(const Task& t);
  // Whether its networks multiply in bf16 (which CPU class its bits belong to).
  bool (*bf16_products)(const Task& t, const Profile& p);
  bool stores_weights;  // the results file may keep its weights (the environment's store_weights)
  // The task's own fields in its record (what its table's columns read besides its results).
  void (*describe)(const Task& t, TaskRecord& r);
  // Computes the task: inputs from ctx, outputs into r (through experiment/task_outputs.h, the one
  // path by which fresh and resumed runs hand results to later tasks).
  void (*run)(const Task& t, RunContext& ctx, TaskRecord& r);
  // The results table it contributes (/tables/<name>, <name>.csv); no name: none.
  CellTableSpec table;
  // Records of an older engine: whether one lacks fields its table now reads, and the step that
  // fills them in (both null: its records have not changed).
  bool (*lacks_fields)(const TaskRecord& r) = nullptr;
  bool (*complete_fields)(TaskRecord& r) = nullptr;
  // Compiles what its runner reads of the profile into the task's configuration
  // (experiment/task_config.h): its hyper-parameters and its kind's own section. add_task calls it
  // once per task, then adds the settings text, the bf16 choice and a noisy teacher's point; null:
  // the kind reads nothing more.
  void (*compile)(const Task& t, const Profile& p, TaskConfig& c) = nullptr;
};

// Registers a kind with the engine, from a static object in the kind's own file:
//   const TaskKindRegistration registered(tpa_kind());
// Throws std::logic_error (at start-up) for a declaration missing a function or a name taken.
struct TaskKindRegistration {
  explicit TaskKindRegistration(const TaskKindSpec& kind);
};

// Every registered kind, by name.
const std::vector<const TaskKindSpec*>& task_kinds();

// The bf16 choices kinds make: their environment's precision (at the task's hyper-parameter
// point), or never (a linear probe on a stored embedding).
bool env_precision_is_bf16(const Task& t, const Profile& p);
bool never_bf16(const Task& t, const Profile& p);

// The compile steps kinds share: the environment's hyper-parameters at the task's point.
void compile_env_point(const Task& t, const Profile& p, TaskConfig& c);

// The most tasks a plan may hold: about 8 times the paper's whole protocol.
inline constexpr size_t kMaxPlanTasks = 50000;

// Adds t to the plan unless a task with its key is there (a task shared by several cells appears
// once), after the inputs it reads; sets its key, deps and cost from its kind. Returns its index.
// Throws std::invalid_argument past kMaxPlanTasks.
int add_task(Plan& plan, const Profile& p, Task t);

// The record fields every task carries: its environment and seed (a kind's `describe` for tasks
// with nothing more to say, and the start of every other kind's).
void describe_env_and_seed(const Task& t, TaskRecord& r);

// Computes the task, returning its record (timing included). Throws std::runtime_error naming
// the task on any failure (divergence, bad inputs).
TaskRecord run_task(const Task& t, RunContext& ctx);

// Whether the task's networks multiply in bf16 (its kind said, when it was compiled).
bool runs_bf16_products(const Task& t);
// The CPU class whose bits the task's result has (probes/cpu_class.h; with the bf16 backend
// when its products run in bf16): recorded as its record's "cpu_class", and the class the task
// cache files it under.
std::string task_cpu_class(const Task& t);

// The results file's tables from its records: every kind's table, then the cross-kind ones, with
// the roofs the run measured (results_file.h: build_tables).
ResultTables result_tables(const std::vector<TaskRecord>& records, const Roofs& roofs = {});

}  // namespace sirl
