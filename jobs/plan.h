// The profile's grid expanded into a DAG of tasks (jobs/task.h). Shared inputs appear once: one
// VAE per (env, seed), one representation per (env, seed, variant, N) feeding every FPE and TPA
// cell that needs it. Task keys are stable strings; each task's RNG seed derives from its key.
#pragma once
#include <cstdint>

#include "jobs/profile.h"
#include "jobs/task.h"

namespace sirl {

// Throws std::invalid_argument for an inconsistent profile (e.g. a TPA variant with no rep).
Plan make_plan(const Profile& p);

}  // namespace sirl
