// A Checkpointer that keeps the last training snapshot in memory, for the tests of resumable
// trainings: with `stop_after` = k it ends the training (as a kill would) right after saving
// epoch k, by throwing Interrupted.
#pragma once
#include <optional>

#include "engine/checkpoint.h"

namespace sirl::test {

struct Interrupted {};

struct MemoryCheckpointer : Checkpointer {
  std::optional<TrainingSnapshot> saved;
  int stop_after = -1, saves = 0;
  bool load(TrainingSnapshot& out) override {
    if (!saved) return false;
    out = *saved;
    return true;
  }
  bool due() override { return true; }
  void save(const TrainingSnapshot& s) override {
    saved = s;
    ++saves;
    if (s.epoch == stop_after) throw Interrupted{};
  }
};

}  // namespace sirl::test
