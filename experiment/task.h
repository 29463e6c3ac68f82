// A task of the plan and the plan itself: the DAG of tasks a profile asks for. A task's kind is a
// handle on the kind's declaration (experiment/task_kinds.h), which lives in the kind's own file.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "experiment/profile.h"

namespace sirl {

struct TaskKindSpec;
struct TaskConfig;  // experiment/task_config.h

// Which kind a task is: its declaration, compared by identity. Converts from the declaration
// (`t.kind = tpa_kind()`); an unset kind throws std::logic_error when read.
class TaskKind {
 public:
  TaskKind() = default;
  TaskKind(const TaskKindSpec& spec) : spec_(&spec) {}  // NOLINT: a kind is its declaration
  const TaskKindSpec& spec() const;
  const TaskKindSpec* operator->() const { return &spec(); }
  const char* name() const;
  friend bool operator==(TaskKind a, TaskKind b) { return a.spec_ == b.spec_; }

 private:
  const TaskKindSpec* spec_ = nullptr;
};

struct Task {
  std::string
      key;  // set by add_task from the kind's key scheme: "grid/s0/vae", ".../tpa/M50/frozen"
  TaskKind kind;
  std::string env;
  int64_t seed = 0;
  Variant variant;  // rep, fpe, tpa
  int64_t N = 0;    // 0 for methods that use no queries (vae, random)
  int64_t M = 0;    // tpa
  bool frozen = true;
  bool in_main = false, in_ablation = false;  // tpa: a cell of [tpa] (Fig. 5), [ablation] (Fig. 7)
  std::string participant;                    // study_heldout, study_tpa
  // The teacher who answered the queries: "" = the profile's main teacher, else a noisy
  // teacher's tag ("beta=1"; Profile::robustness). Only for cells that learn from answers.
  std::string teacher;
  // The hyper-parameter point it runs at: "" = the environment's base point, else a tag of
  // Profile::hyper_points ("sirl.epochs=300"). add_task keeps it only on a task whose settings
  // or inputs the point changes (a φ is shared by every point of a "tpa.lr" axis), and its key
  // then carries it after the seed: "grid/s0/sirl.epochs=300/sirl/N100/rep".
  std::string hyper;
  // Everything its runner reads of the profile (experiment/task_config.h), compiled once when it
  // is planned (add_task, by its kind's `compile`): its hyper-parameters at its point, its
  // settings text for the digest, and its kind's own section. Runners receive no Profile.
  std::shared_ptr<const TaskConfig> config;
  // *config; std::logic_error when the task was not planned by add_task.
  const TaskConfig& compiled() const;
  // compiled().hyper; std::logic_error for a kind that reads none.
  const Hyper& hyper_values() const;
  std::vector<int> deps;  // indices into Plan::tasks (set by add_task)
  // The key of the input of each kind it reads, by kind name (set by add_task): a runner finds
  // its φ, VAE or active queries here, whichever point they were planned at.
  std::map<std::string, std::string> input_keys;
  // The keys of every task it reads, in the order its kind's `inputs` lists them (set by
  // add_task): for a kind that reads several tasks of one kind (the study's analysis).
  std::vector<std::string> input_keys_in_order;
  // The key of its input of kind k (std::out_of_range if it reads none).
  const std::string& input(TaskKind k) const;
  double flops = 0;  // estimated floating-point operations executed (add_task)
  // Every epoch of every schedule: more than `flops` where the engine ends training early by
  // rule (SIRL's exact skip, converged reward heads; experiment/expected_epochs.h).
  double protocol_flops = 0;
  double bytes = 0;         // estimated peak working set (add_task)
  double stream_bytes = 0;  // estimated main-memory traffic over the task (add_task; 0: in cache)
  int threads = 1;          // cores its kernels use: set by the scheduler, not part of its key
};

struct Plan {
  std::vector<Task> tasks;
  std::map<std::string, int> index;  // key → position
  int count(TaskKind k) const;
  double flops(TaskKind k) const;
  double protocol_flops(TaskKind k) const;
};

}  // namespace sirl
