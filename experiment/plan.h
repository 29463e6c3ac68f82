// The profile's grid expanded into a DAG of tasks (experiment/task.h). Shared inputs appear once:
// one VAE per (env, seed), one representation per (env, seed, variant, N) feeding every FPE and TPA
// cell that needs it. Task keys are stable strings; each task's RNG seed derives from its key.
#pragma once
#include <cstdint>

#include "experiment/profile.h"
#include "experiment/task.h"

namespace sirl {

// Throws std::invalid_argument for an inconsistent profile (e.g. a TPA variant with no rep).
Plan make_plan(const Profile& p);

}  // namespace sirl
