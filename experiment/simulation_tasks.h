// The paper's simulation experiments (Fig. 4, 5 and 7) as task kinds, per (environment, seed):
//   <env>/s<seed>/vae                         a VAE over Ξ (pre-training, the VAE baseline)
//   <env>/s<seed>/<variant>[/N<N>]/rep        a representation φ (N only for query methods)
//   <env>/s<seed>/<variant>[/N<N>]/fpe        FPE of that φ
//   <env>/s<seed>/<variant>[/N<N>]/tpa/M<M>/{frozen,unfrozen}   TPA of that φ at M pairs
//   <env>/s<seed>/<variant>[/N<N>]/tpa/M<M>/linear   the same under linear evaluation
// <variant> is a method's, or a reference's (truth, raw: no rep task, φ is a function of Ξ).
// and the robustness cells of a noisy teacher (robust_fpe, robust_tpa; its φ is a rep task):
//   <env>/s<seed>/<teacher>/<variant>[/N<N>]/{rep,fpe,tpa/...}      <teacher> = "beta=1", …
// (a method that learns from no answers — VAE, Random — has one φ for every teacher, but its
// TPA heads learn from the teacher's labels).
// Each function returns a kind's whole declaration (experiment/task_kinds.h), registered with the
// engine by this file.
#pragma once
#include <cstdint>
#include <string>

#include "experiment/task_kinds.h"

namespace sirl {

const TaskKindSpec& vae_kind();
const TaskKindSpec& rep_kind();
const TaskKindSpec& fpe_kind();
const TaskKindSpec& tpa_kind();
// <env>/s<seed>/<variant>[/N<N>]/tpa/M<M>/linear: TPA of that φ under linear evaluation
// (engine/linear_tpa.h), rows of /tables/tpa with protocol "linear".
const TaskKindSpec& linear_tpa_kind();
const TaskKindSpec& robust_fpe_kind();
const TaskKindSpec& robust_tpa_kind();
// <env>/s<seed>[/<teacher>]/active/<rule>: the triplets an active variant of SIRL learns from
// (engine/active_queries.h), [queries] similarity of them, in the order asked.
const TaskKindSpec& active_kind();

// The rate classes `sirl plan` times SIRL's training and a cell's reward heads with
// (experiment/calibration.h); the user study's kinds spend their FLOPs in them too.
const RateClass& sirl_training_rate();
const RateClass& tpa_training_rate(bool frozen);

// Adds the simulation grid's tasks to the plan: every cell of [fpe], [tpa], [ablation] and
// [robustness] with the VAEs, representations and active selections they read
// (experiment/simulation_plan.cpp).
void add_simulation_tasks(Plan& plan, const Profile& p);

// The keys other code looks tasks up by (the VAE and φ a cell reads).
std::string vae_key(const std::string& env, int64_t seed);
std::string rep_key(const std::string& env, int64_t seed, const Variant& v, int64_t N,
                    const std::string& teacher = "");

// A cell of the experiment (a rep, fpe or tpa task, or a robustness cell) on φ of (env, seed,
// v, N) with queries answered by `teacher`, fields set: N is dropped for methods that use no
// queries (their φ is shared by every N), and so is the teacher for their rep and FPE.
Task experiment_cell(TaskKind kind, const std::string& env, int64_t seed, const Variant& v,
                     int64_t N, const std::string& teacher = "");

// Fills the cell fields engines before 0.8.0 did not record (selection, teacher, best_mode) from
// the record's variant and frozen flag, so their files still merge and export. Returns whether it
// changed anything (lacks_cell_fields said it would).
bool lacks_cell_fields(const TaskRecord& r);
bool complete_cell_fields(TaskRecord& r);

}  // namespace sirl
