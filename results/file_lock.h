// One writer per file: an exclusive flock on FILE.lock, held for the holder's life and released
// by the kernel if the process dies. The holder writes "<pid> <command>" into the lock file so a
// second writer can name it, and removes the file when it is done (a lock left by a process that
// died is taken over by the next). Removing it while others may have it open is safe because a
// taker checks, once it holds the flock, that the path still names the file it locked, and
// starts over if not: two writers can never hold two different inodes of one name.
// Used by every command that writes a results, dataset or study file.
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
  bool try_lock(const std::string& file, const std::string& holder, const std::string& advice);
  std::string path_;
  int fd_ = -1;
};

}  // namespace sirl
