#include "jobs/task_kinds.h"

#include <stdexcept>

#include "jobs/study_tasks.h"

namespace sirl {

const std::vector<TaskKindSpec>& task_kinds() {
  static const std::vector<TaskKindSpec> all{
      {TaskKind::vae, "vae", "a VAE over Ξ per (env, seed): pre-training and the VAE baseline",
       run_vae_task},
      {TaskKind::rep, "rep", "a representation φ per (env, seed, method, N), its embedding of Ξ",
       run_rep_task},
      {TaskKind::fpe, "fpe", "FPE of one φ: a linear probe's held-out error", run_fpe_task},
      {TaskKind::tpa, "tpa", "TPA of one φ at M pairs, frozen or unfrozen: 20 reward heads",
       run_tpa_task},
      {TaskKind::study_rep, "study_rep",
       "user study: SIRL on the pooled answers or Random, per training seed, with its FPE",
       run_study_rep_task},
      {TaskKind::study_heldout, "study_heldout",
       "user study: SIRL without one participant's answers", run_study_heldout_task},
      {TaskKind::study_tpa, "study_tpa",
       "user study: one participant's Real and Held-out TPA (cross-validated)", run_study_tpa_task},
      {TaskKind::study_simulated, "study_simulated",
       "user study: TPA on simulated perfect preferences", run_study_simulated_task},
  };
  return all;
}

const TaskKindSpec& task_kind(TaskKind k) {
  for (const auto& s : task_kinds())
    if (s.kind == k) return s;
  throw std::logic_error("task kind without a registration");
}

}  // namespace sirl
