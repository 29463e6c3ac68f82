// The task cache: finished tasks filed by content (digest, experiment/task_digest.h) and CPU class,
// in one directory that outlives any results file. `sirl run` reads what its plan's digests find
// there and commits what it computes; several runs, of one profile or of different ones, share
// it, even at once:
//   <dir>/<file>.h5            one committed task each (results/task_store.h), id <digest>-<class>
//   <dir>/checkpoints/         trainings in progress, by digest (jobs/task_checkpoints.h)
//   <dir>/locks/<digest>.lock  held (flock) while a process computes that task
//   <dir>/runs/<host>.<pid>    the digests a running process needs, held (flock) while it runs
//   <dir>/gc.lock              the gate: `sirl gc` holds it exclusively while it reads runs/ and
//                              sweeps; a run holds it shared from before it lists the cache until
//                              its needs are declared, so no sweep removes what a starting run saw
// A task is computed by one process at a time: a second run that reaches it waits for the
// first's commit and reads it. `sirl gc` removes what no given profile and no running process
// needs.
#pragma once
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "results/task_store.h"

namespace sirl {

class TaskCache {
 public:
  // Opens (creating) the directory, waiting while `sirl gc` sweeps it. Throws H5Error if it
  // cannot.
  explicit TaskCache(std::filesystem::path dir);
  ~TaskCache();
  TaskCache(const TaskCache&) = delete;
  TaskCache& operator=(const TaskCache&) = delete;

  const std::filesystem::path& dir() const { return store_.dir(); }
  TaskStore& store() { return store_; }

  // The id a result of `digest` computed on `cpu_class` is filed under: "<digest>-<8 hex>".
  static std::string id(const std::string& digest, const std::string& cpu_class);
  // The id of a stored result of `digest`: the one computed on `cpu_class`, else (any_class)
  // one computed on another class; "" when there is none.
  std::string find(const std::string& digest, const std::string& cpu_class, bool any_class) const;

  // Declares the digests this process needs until it ends (sirl gc keeps them), and lets a
  // waiting gc in.
  void register_needs(const std::vector<std::string>& digests);

  // Exclusive right to compute one task: waits while another process holds it.
  class Claim {
   public:
    Claim(Claim&& o) noexcept : fd_(o.fd_) { o.fd_ = -1; }
    ~Claim();

   private:
    friend class TaskCache;
    explicit Claim(int fd) : fd_(fd) {}
    int fd_;
  };
  // `waiting` is called once if the claim must wait for another process.
  Claim claim(const std::string& digest, const std::function<void()>& waiting = {}) const;

 private:
  int gate_fd_;  // gc.lock, held shared until register_needs (declared first: taken before the
                 // store lists the folder)
  TaskStore store_;
  int needs_fd_ = -1;
  std::filesystem::path needs_path_;
};

// What `sirl gc` found and did.
struct GcSummary {
  int64_t kept = 0, removed = 0, held = 0;  // held: kept for a running process
  uint64_t kept_bytes = 0, removed_bytes = 0;
};
// Removes from the cache at `dir` every committed task and checkpoint whose digest is not in
// `keep`, is not needed by a running process (runs/) and is not being computed (locks/); with
// `dry_run`, only counts. Never follows symbolic links. Throws std::runtime_error on an
// unreadable directory.
GcSummary collect_garbage(const std::filesystem::path& dir, const std::set<std::string>& keep,
                          bool dry_run);

}  // namespace sirl
