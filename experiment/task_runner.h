// Runs one task of the plan: a pure function of the task (its key) and its inputs.
// RunContext holds what tasks share — the environment's dataset, each seed's query bundle, the
// VAEs and representations other tasks need — built lazily and safely from many threads, and
// reloaded from committed records when a resumed run needs the output of an earlier one.
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "datasets/dataset.h"
#include "datasets/query_bundle.h"
#include "datasets/study.h"
#include "engine/checkpoint.h"
#include "engine/representation.h"
#include "engine/train_vae.h"
#include "experiment/profile.h"
#include "experiment/task.h"
#include "results/task_record.h"

namespace sirl {

class RunContext {
 public:
  // `load` fetches a committed record by key (for resumed runs); may throw if absent.
  // The profile builds the shared data only (Ξ, the query bundles, the cohort): a runner reads
  // its settings from its task's compiled configuration (experiment/task_config.h), never here.
  RunContext(const Profile& p, std::function<TaskRecord(const std::string&)> load);
  const Dataset& dataset(const std::string& env);
  // The queries of (env, seed) answered by `teacher` ("" = the profile's main teacher).
  const QueryBundle& bundle(const std::string& env, int64_t seed, const std::string& teacher = "");
  // The user study's simulated cohort ([study]) and its trajectory space.
  const Study& study();
  const Dataset& study_dataset();
  std::shared_ptr<const Representation> representation(const std::string& key);
  std::shared_ptr<const VaeModel> vae(const std::string& key);
  void keep(const std::string& key, std::shared_ptr<const Representation> r);
  void keep(const std::string& key, std::shared_ptr<const VaeModel> v);
  // The triplets an `active` task chose, in the order asked.
  std::shared_ptr<const TripletSet> triplets(const std::string& key);
  void keep(const std::string& key, std::shared_ptr<const TripletSet> q);
  // The committed record of a task this one reads (every input is committed before its readers
  // run, in this process, another rank or an earlier run). Throws std::runtime_error if absent.
  TaskRecord record(const std::string& key) { return load_(key); }
  // Drops a cached output once no pending task needs it (bounded memory on long runs).
  void release(const std::string& key);
  // Where a task's training saves and resumes its state (jobs/task_checkpoints.h); without a
  // source, trainings run without checkpoints.
  void set_checkpoints(std::function<std::unique_ptr<Checkpointer>(const std::string&)> source) {
    checkpoints_ = std::move(source);
  }
  std::unique_ptr<Checkpointer> checkpointer(const std::string& task_key) const {
    return checkpoints_ ? checkpoints_(task_key) : nullptr;
  }

 private:
  const Profile& profile_;
  std::function<TaskRecord(const std::string&)> load_;
  std::function<std::unique_ptr<Checkpointer>(const std::string&)> checkpoints_;
  std::mutex mu_;
  std::map<std::string, std::shared_ptr<const Dataset>> datasets_;
  std::map<std::string, std::shared_ptr<const QueryBundle>> bundles_;
  std::map<std::string, std::shared_ptr<const Representation>> reps_;
  std::map<std::string, std::shared_ptr<const VaeModel>> vaes_;
  std::map<std::string, std::shared_ptr<const TripletSet>> triplets_;
  std::shared_ptr<const Study> study_;
  std::shared_ptr<const Dataset> study_dataset_;
  std::map<std::string, std::unique_ptr<std::once_flag>> once_;
  std::once_flag& once(const std::string& key);
};

// The seed every task of (env, seed) derives its streams from (keyed by the environment's
// stream_name(): its own name unless it reproduces another): all methods of one seed start
// from the same φ initialisation and the same TPA heads (common random numbers).
uint64_t task_seed(const std::string& env, int64_t seed, const char* stream);

}  // namespace sirl
