// Crash-safe per-task commits: every finished task becomes its own small HDF5 file in a store
// directory, written to a temporary name, fsync'ed and renamed into place. A kill -9 at any
// moment leaves each file either complete or absent, so a rerun trusts whatever it finds.
// A commit is filed under an id: the task's key (training checkpoints, tests), or its content
// digest and CPU class (`sirl run`'s cache, experiment/task_digest.h), so several runs of different
// profiles, even at once, share one directory.
#pragma once
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "results/task_record.h"

namespace sirl {

class TaskStore {
 public:
  // Opens (creating if needed) the directory and indexes the records already committed there.
  // Leftover temporary files of an interrupted commit are removed. Only files named as the store
  // names its own ("<16 hex digits>.h5", and their temporary names) are read or ever removed:
  // anything else in the folder (a results file, notes) is left alone.
  explicit TaskStore(std::filesystem::path dir);
  // Whether a file name is one the store writes: a commit, or a commit's temporary file.
  static bool is_commit_name(const std::string& name);
  static bool is_temporary_name(const std::string& name);
  const std::filesystem::path& dir() const { return dir_; }
  // Whether a record is filed under `id`: in this object's index, or committed since by another
  // process (then indexed).
  bool has(const std::string& id) const;
  // Every id indexed (those found when the store was opened and those committed since).
  std::vector<std::string> keys() const;
  // Atomic and durable; thread-safe. Files r under `id` (default: its key), replacing a record
  // filed there.
  void commit(const TaskRecord& r, const std::string& id);
  void commit(const TaskRecord& r) { commit(r, r.key); }
  // Removes a record (no error if absent); thread-safe.
  void remove(const std::string& id);
  bool empty() const;
  // The record filed under `id`, whose task key must be `key`; verified (frame checksum, then
  // the record's own), and removed if corrupted. Throws H5Error naming the task.
  TaskRecord load(const std::string& id, const std::string& key) const;
  TaskRecord load(const std::string& key) const { return load(key, key); }
  // Checks the file filed under `id` against its frame's checksum without parsing it (a
  // corrupted file is removed). Returns "" if sound, else why not (naming `key`).
  std::string verify(const std::string& id, const std::string& key) const;
  // The bytes the record filed under `id` takes on disk (0 if absent).
  uint64_t bytes(const std::string& id) const;
  // The ids committed in `dir`, read from the files' frames only: no file is created, removed
  // or parsed (`sirl plan`, `sirl gc`). Empty if `dir` does not exist.
  static std::vector<std::string> ids_in(const std::filesystem::path& dir);
  // The file a record filed under `id` is committed to.
  static std::filesystem::path file_for(const std::filesystem::path& dir, const std::string& id);
  // Reads a record committed (possibly by another process) into `dir`; throws H5Error if absent.
  static TaskRecord load_from(const std::filesystem::path& dir, const std::string& id,
                              const std::string& key);
  static TaskRecord load_from(const std::filesystem::path& dir, const std::string& key) {
    return load_from(dir, key, key);
  }
  // A small text file beside the records (e.g. the profile the run started with).
  void write_manifest(const std::string& name, const std::string& text);
  std::string read_manifest(const std::string& name) const;  // "" when absent

 private:
  std::filesystem::path dir_;
  mutable std::mutex mu_;
  mutable std::map<std::string, std::filesystem::path> index_;
};

// The checksum each commit stores beside its record (attribute /r@record_checksum) and load()
// verifies: a corrupted task file is removed and refused with its task's name. XXH3-128 (32 hex);
// record_checksum_fnv is the 16-digit one of engines up to 0.7.0, still verified.
std::string record_checksum(const TaskRecord& r);
std::string record_checksum_fnv(const TaskRecord& r);

// Test hook: with SIRL_CRASH_AFTER_COMMITS=k in the environment the process ends abruptly (exit
// code 137, no cleanup) right after its k-th commit, so crash tests kill at an exact point.
void crash_point_after_commit();
// Held from a commit's rename to its crash_point_after_commit() call: engaged only when the hook
// is on, so that commits from several threads count exactly.
std::unique_lock<std::mutex> crash_point_serialise();

}  // namespace sirl
