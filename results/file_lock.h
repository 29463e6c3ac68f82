// One writer per file: an exclusive flock on FILE.lock, held for the holder's life and released
// by the kernel if the process dies. The holder writes "<pid> <command>" into the lock file so a
// second writer can name it. (The lock file stays: unlinking it would let two later writers lock
// two different inodes.) Used by `sirl run` for its --out and by `sirl study serve` for its study.
#pragma once
#include <stdexcept>
#include <string>

namespace sirl {

// Thrown when another process holds the lock; the message names the file, what holds it (with
// its pid when known) and what to do.
struct FileBusy : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

class FileLock {
 public:
  // `holder` names this command ("sirl run", "sirl study serve"), written into the lock for a
  // refused process to name; `advice` is what a refused process can do (in its message). Throws
  // std::runtime_error if the lock file cannot be created.
  FileLock(const std::string& file, const std::string& holder, const std::string& advice);
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace sirl
