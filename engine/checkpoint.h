// A long training's state at an epoch boundary, so that a run killed mid-training continues it
// instead of starting again: weights, Adam moments and step, random streams, the curves so far.
// A training resumed from a snapshot ends bit-identical to one that was never interrupted.
// The engine only fills and reads snapshots; where they are kept (a file next to the task
// commits) is the job layer's business (experiment/task_runner.cpp).
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "kernels/adam.h"
#include "kernels/rng.h"

namespace sirl {

struct TrainingSnapshot {
  int epoch = 0;                                       // epochs completed
  std::map<std::string, std::vector<float>> floats;    // weights, moments, curves
  std::map<std::string, double> numbers;               // sums, FLOP counters, step counts
  std::map<std::string, std::vector<uint64_t>> words;  // random-stream states

  void put_rng(const std::string& name, const Rng& r) {
    const auto s = r.state();
    words[name].assign(s.begin(), s.end());
  }
  // Throws std::runtime_error when the snapshot lacks `name` (or it has the wrong size): a
  // snapshot from another training is never half-applied.
  void get_rng(const std::string& name, Rng& r) const;
  const std::vector<float>& get(const std::string& name, size_t size) const;
  double number(const std::string& name) const;
};

// An optimiser's part of a snapshot: the weights, Adam's moments and step, under `name`/.
void put_adam(TrainingSnapshot& s, const std::string& name, const std::vector<float>& params,
              const AdamState& adam);
void get_adam(const TrainingSnapshot& s, const std::string& name, std::vector<float>& params,
              AdamState& adam);

// Where a training saves its state and finds it again.
class Checkpointer {
 public:
  virtual ~Checkpointer() = default;
  // The state an interrupted earlier attempt saved, if any.
  virtual bool load(TrainingSnapshot& out) = 0;
  // Asked after each epoch but the last: is a save due (e.g. minutes since the last one)?
  virtual bool due() = 0;
  virtual void save(const TrainingSnapshot& s) = 0;
};

// Thrown where work ends because a stop was requested (a checkpointer's `save` when the run was
// asked to stop, a task not started: jobs/stop_request.h): the run treats it as a stop, not as a
// failure of the task.
struct StopRequested : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// What a training keeps between epochs besides the loop's own state (the epoch, the curve and
// the order stream, which run_epochs saves itself): `save` adds it to a snapshot, `restore`
// takes it back.
struct ResumableState {
  Checkpointer* checkpointer = nullptr;  // nullptr: no checkpoints
  std::function<void(TrainingSnapshot&)> save;
  std::function<void(const TrainingSnapshot&)> restore;
};

// The state of most trainings: weights and Adam under `name`/, and the FLOP counter.
ResumableState adam_resumable(Checkpointer* checkpointer, const std::string& name,
                              std::vector<float>& params, AdamState& adam, double& flops);

}  // namespace sirl
