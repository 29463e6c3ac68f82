// Crash-safe per-task commits: every finished task becomes its own small HDF5 file in a staging
// directory, written to a temporary name, fsync'ed and renamed into place. A kill -9 at any
// moment leaves each file either complete or absent, so a rerun trusts whatever it finds.
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
  // Leftover temporary files of an interrupted commit are removed.
  explicit TaskStore(std::filesystem::path dir);
  const std::filesystem::path& dir() const { return dir_; }
  bool has(const std::string& key) const;
  std::vector<std::string> keys() const;
  // Atomic and durable; thread-safe. Overwrites a record of the same key.
  void commit(const TaskRecord& r);
  // Removes a record (no error if absent); thread-safe.
  void remove(const std::string& key);
  bool empty() const;
  TaskRecord load(const std::string& key) const;
  // Reads a record committed (possibly by another process) into `dir`; throws H5Error if absent.
  static TaskRecord load_from(const std::filesystem::path& dir, const std::string& key);
  // A small text file beside the records (e.g. the profile the run started with).
  void write_manifest(const std::string& name, const std::string& text);
  std::string read_manifest(const std::string& name) const;  // "" when absent

 private:
  static std::filesystem::path file_for(const std::filesystem::path& dir, const std::string& key);
  std::filesystem::path dir_;
  mutable std::mutex mu_;
  std::map<std::string, std::filesystem::path> index_;
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
