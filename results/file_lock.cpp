#include "results/file_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace sirl {

FileLock::FileLock(const std::string& file, const std::string& holder, const std::string& advice)
    : path_(file + ".lock") {
  // O_NOFOLLOW: a link planted at OUT.lock must not make us write our pid into its target.
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd_ < 0 && errno == ELOOP)
    throw std::runtime_error(path_ +
                             " is a symbolic link; sirl creates this file itself and does "
                             "not write through links: remove it");
  if (fd_ < 0)
    throw std::runtime_error(path_ + ": cannot create the lock file: " + std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char buf[32] = {};
    const ssize_t n = ::pread(fd_, buf, sizeof buf - 1, 0);
    ::close(fd_);
    if (err == EWOULDBLOCK)
      throw FileBusy(file + " is in use by another " + holder +
                     (n > 0 ? " (pid " + std::string(buf, size_t(n)) + ")" : std::string()) + "; " +
                     advice);
    throw std::runtime_error(path_ + ": cannot lock: " + std::strerror(err));
  }
  const std::string pid = std::to_string(::getpid());
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, pid.data(), pid.size(), 0) < 0) {
    // the lock holds without the pid; a second writer just cannot name us
  }
}

FileLock::~FileLock() {
  ::close(fd_);
}

}  // namespace sirl
