#include "experiment/task_digest.h"

#include <cstdio>

#include "datasets/exact_text.h"
#include "experiment/task_config.h"
#include "experiment/task_kinds.h"
#include "results/durable.h"
#include "results/task_record.h"

namespace sirl {

std::string task_digest_text(const Task& t, const std::vector<std::string>& input_digests,
                             const std::vector<std::string>& input_keys) {
  const TaskKindSpec& kind = t.kind.spec();
  std::string s = "sirl task\nnumerics " + std::to_string(kNumericsVersion) + "\nkind " +
                  kind.name + "\nkey " + t.key + "\n";
  // The record's own fields, as its describe writes them (a cell joining the ablation grid
  // changes its in_ablation column, so its record).
  TaskRecord d;
  kind.describe(t, d);
  for (const auto& [k, v] : d.text) s += "field " + k + " = " + v + "\n";
  for (const auto& [k, v] : d.num) s += "field " + k + " = " + exact_number(v) + "\n";
  s += "stream_bytes " + exact_number(t.stream_bytes) + "\n";  // recorded beside its results
  s += t.compiled().settings;  // compiled from p when the task was planned
  for (size_t i = 0; i < input_digests.size(); ++i)
    s += "input " + input_keys[i] + " " + input_digests[i] + "\n";
  return s;
}

std::vector<std::string> task_digests(const Plan& plan) {
  std::vector<std::string> out(plan.tasks.size());
  for (size_t i = 0; i < plan.tasks.size(); ++i) {
    const Task& t = plan.tasks[i];
    std::vector<std::string> dig, keys;
    for (int d : t.deps) {  // inputs precede their readers in a plan
      dig.push_back(out[size_t(d)]);
      keys.push_back(plan.tasks[size_t(d)].key);
    }
    const std::string text = task_digest_text(t, dig, keys);
    out[i] = bytes_digest(text.data(), text.size());
  }
  return out;
}

}  // namespace sirl
