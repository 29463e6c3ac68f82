// Training checkpoints of a run's tasks on disk: <out>.tasks/checkpoints/, one file per task in
// the task-commit format (framed, checksummed, written atomically), saved at the end of an epoch
// when `interval` seconds have passed since the task's last save, and removed once the task
// itself is committed. A rerun of an interrupted run continues each training from its file, to
// the same bits as an uninterrupted run (engine/checkpoint.h).
#pragma once
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "engine/checkpoint.h"
#include "results/task_store.h"

namespace sirl {

class CheckpointStore {
 public:
  // interval_seconds 0: after every epoch (tests); a negative interval turns checkpoints off.
  CheckpointStore(std::filesystem::path dir, double interval_seconds);
  // A checkpointer for one task's training, filed under `id` (its task digest) and named `label`
  // (its key) in messages; nullptr when checkpoints are off. Under a stop request
  // (jobs/stop_request.h) it saves at the next epoch end and throws StopRequested.
  std::unique_ptr<Checkpointer> for_task(const std::string& id, const std::string& label);
  // The task is committed: its checkpoint is no longer needed.
  void remove(const std::string& key) { store_.remove(key); }
  bool empty() const { return store_.empty(); }
  // The tasks with a saved state (each resumes from it when it runs).
  std::vector<std::string> keys() const { return store_.keys(); }
  // Called as a task continues from its checkpoint, with its label and the FLOPs its training had
  // executed before (the snapshot's "train_flops"; 0 when the snapshot does not count them).
  using ResumeHook = std::function<void(const std::string& label, double flops_before)>;
  void on_resume(ResumeHook hook) { on_resume_ = std::move(hook); }

 private:
  TaskStore store_;
  double interval_;
  ResumeHook on_resume_;
};

// The record a snapshot is stored as, and back (throws std::runtime_error if it is not one).
TaskRecord snapshot_record(const std::string& key, const TrainingSnapshot& s);
TrainingSnapshot record_snapshot(const TaskRecord& r);

}  // namespace sirl
