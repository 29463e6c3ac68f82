// What each task kind of the paper's grid is expected to cost (TaskKindSpec::cost;
// experiment/cost_model.h is the model they share): t.flops (what it is expected to execute),
// t.protocol_flops (every epoch of every schedule), t.bytes (its peak working set) and
// t.stream_bytes (its main-memory traffic).
#pragma once
#include "engine/active_queries.h"
#include "experiment/task.h"

namespace sirl {

void vae_cost(Task& t, const Profile& p);
void rep_cost(Task& t, const Profile& p);
void fpe_cost(Task& t, const Profile& p);
void tpa_cost(Task& t, const Profile& p);
void linear_tpa_cost(Task& t, const Profile& p);
void active_cost(Task& t, const Profile& p);

// What an active task runs with (its runner and its cost read the same): the environment's
// [active] rounds, its rule, the uniform set's budget and the task's hyper-parameters: compiled
// once into the task's configuration (TaskConfig::active).
ActiveConfig active_config(const Task& t, const Profile& p, const Hyper& hyper);

}  // namespace sirl
