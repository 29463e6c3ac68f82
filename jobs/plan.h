// The profile's grid expanded into a DAG of tasks. Shared inputs appear once: one VAE per
// (env, seed), one representation per (env, seed, variant, N) feeding every FPE and TPA cell
// that needs it. Task keys are stable strings; each task's RNG seed derives from its key.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "jobs/profile.h"

namespace sirl {

// The kinds of task (jobs/task_kinds.h declares each: key, inputs, cost, runner, table).
enum class TaskKind {
  vae,
  rep,
  fpe,
  tpa,
  study_rep,
  study_heldout,
  study_tpa,
  study_simulated,
  robust_fpe,
  robust_tpa,
  active
};
const char* kind_name(TaskKind k);

struct Task {
  std::string
      key;  // set by add_task from the kind's key scheme: "grid/s0/vae", ".../tpa/M50/frozen"
  TaskKind kind = TaskKind::rep;
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
  std::vector<int> deps;  // indices into Plan::tasks (set by add_task)
  // The key of the input of each kind it reads (set by add_task): a runner finds its φ, VAE or
  // active queries here, whichever point they were planned at.
  std::map<TaskKind, std::string> input_keys;
  double flops = 0;  // estimated floating-point operations executed (add_task)
  // Every epoch of every schedule: more than `flops` where the engine ends training early by
  // rule (SIRL's exact skip, converged reward heads; jobs/expected_epochs.h).
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

// Throws std::invalid_argument for an inconsistent profile (e.g. a TPA variant with no rep).
Plan make_plan(const Profile& p);

// Training cost: forward + backward ≈ 3× the forward FLOPs, per row per epoch.
double train_flops(const MlpShape& s, int64_t rows_per_epoch, int epochs);

}  // namespace sirl
