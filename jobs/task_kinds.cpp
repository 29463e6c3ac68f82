#include "jobs/task_kinds.h"

#include <stdexcept>

#include "jobs/simulation_tasks.h"
#include "jobs/study_tasks.h"

namespace sirl {

const std::vector<TaskKindSpec>& task_kinds() {
  static const std::vector<TaskKindSpec> all = [] {
    std::vector<TaskKindSpec> k{
        vae_kind(),        rep_kind(),           fpe_kind(),       tpa_kind(),
        study_rep_kind(),  study_heldout_kind(), study_tpa_kind(), study_simulated_kind(),
        robust_fpe_kind(), robust_tpa_kind(),    active_kind()};
    for (size_t i = 0; i < k.size(); ++i)
      if (int(k[i].kind) != int(i) || !k[i].key || !k[i].inputs || !k[i].settings || !k[i].cost ||
          !k[i].rate || !k[i].shard_group || !k[i].describe || !k[i].run)
        throw std::logic_error(std::string("task kind ") + k[i].name +
                               ": out of TaskKind order or a function missing");
    return k;
  }();
  return all;
}

const TaskKindSpec& task_kind(TaskKind k) {
  return task_kinds().at(size_t(k));
}

const char* kind_name(TaskKind k) {
  return task_kind(k).name;
}

void describe_env_and_seed(const Task& t, TaskRecord& r) {
  r.text["env"] = t.env;
  r.num["seed"] = double(t.seed);
  if (!t.hyper.empty()) r.text["hyper_point"] = t.hyper;  // base-point records stay as they were
}

int add_task(Plan& plan, const Profile& p, Task t) {
  const TaskKindSpec& kind = task_kind(t.kind);
  t.deps.clear();
  t.input_keys.clear();
  bool input_at_point = false;
  for (Task& in : kind.inputs(t, p)) {
    const int d = add_task(plan, p, std::move(in));
    const Task& dep = plan.tasks[size_t(d)];
    t.deps.push_back(d);
    t.input_keys[dep.kind] = dep.key;
    input_at_point = input_at_point || !dep.hyper.empty();
  }
  // A hyper-parameter point it does not read (and no input of it read) is the base task.
  if (!t.hyper.empty() && !input_at_point) {
    Task base = t;
    base.hyper.clear();
    if (kind.settings(t, p) == kind.settings(base, p)) t.hyper.clear();
  }
  t.key = kind.key(t);
  if (!t.hyper.empty()) {  // after "<env>/s<seed>/"
    const size_t at = t.key.find('/', t.key.find('/') + 1);
    t.key.insert(at + 1, t.hyper + "/");
  }
  if (auto it = plan.index.find(t.key); it != plan.index.end()) return it->second;
  kind.cost(t, p);
  if (t.protocol_flops < t.flops) t.protocol_flops = t.flops;  // no early end expected
  const int i = int(plan.tasks.size());
  plan.index[t.key] = i;
  plan.tasks.push_back(std::move(t));
  return i;
}

ResultTables result_tables(const std::vector<TaskRecord>& records, const Roofs& roofs) {
  std::vector<CellTableSpec> cells;
  for (const TaskKindSpec& k : task_kinds())
    if (!k.table.name.empty()) cells.push_back(k.table);
  // Records of an older engine (a merge or export of its files) lack fields the tables now
  // carry: complete a copy of them (only then, so a large current file is not copied).
  for (const TaskRecord& r : records) {
    if (!lacks_cell_fields(r)) continue;
    std::vector<TaskRecord> completed = records;
    for (TaskRecord& c : completed) complete_cell_fields(c);
    return build_tables(completed, cells, roofs);
  }
  return build_tables(records, cells, roofs);
}

}  // namespace sirl
