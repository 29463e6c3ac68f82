#include "engine/checkpoint.h"

#include <stdexcept>

namespace sirl {

namespace {
[[noreturn]] void missing(const std::string& what) {
  throw std::runtime_error("training checkpoint: " + what +
                           " (a checkpoint of another training? delete it to start over)");
}
}  // namespace

void TrainingSnapshot::get_rng(const std::string& name, Rng& r) const {
  const auto it = words.find(name);
  if (it == words.end() || it->second.size() != 4) missing("no random stream '" + name + "'");
  r.set_state({it->second[0], it->second[1], it->second[2], it->second[3]});
}

const std::vector<float>& TrainingSnapshot::get(const std::string& name, size_t size) const {
  const auto it = floats.find(name);
  if (it == floats.end()) missing("no array '" + name + "'");
  if (it->second.size() != size)
    missing("array '" + name + "' has " + std::to_string(it->second.size()) + " values, not " +
            std::to_string(size));
  return it->second;
}

double TrainingSnapshot::number(const std::string& name) const {
  const auto it = numbers.find(name);
  if (it == numbers.end()) missing("no number '" + name + "'");
  return it->second;
}

void put_adam(TrainingSnapshot& s, const std::string& name, const std::vector<float>& params,
              const AdamState& adam) {
  s.floats[name + "/params"] = params;
  s.floats[name + "/adam_m"] = adam.m;
  s.floats[name + "/adam_v"] = adam.v;
  s.numbers[name + "/adam_step"] = double(adam.step);
}

void get_adam(const TrainingSnapshot& s, const std::string& name, std::vector<float>& params,
              AdamState& adam) {
  params = s.get(name + "/params", params.size());
  adam.m = s.get(name + "/adam_m", adam.m.size());
  adam.v = s.get(name + "/adam_v", adam.v.size());
  adam.step = int64_t(s.number(name + "/adam_step"));
}

ResumableState adam_resumable(Checkpointer* checkpointer, const std::string& name,
                              std::vector<float>& params, AdamState& adam, double& flops) {
  return {checkpointer,
          [name, &params, &adam, &flops](TrainingSnapshot& snap) {
            put_adam(snap, name, params, adam);
            snap.numbers["train_flops"] = flops;
          },
          [name, &params, &adam, &flops](const TrainingSnapshot& snap) {
            get_adam(snap, name, params, adam);
            flops = snap.number("train_flops");
          }};
}

}  // namespace sirl
