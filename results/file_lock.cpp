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
    char buf[128] = {};
    const ssize_t n = ::pread(fd_, buf, sizeof buf - 1, 0);
    ::close(fd_);
    if (err == EWOULDBLOCK) {
      // The holder wrote "<pid> <command>": name what actually holds it, not what we are.
      const std::string text = n > 0 ? std::string(buf, size_t(n)) : std::string();
      const size_t space = text.find(' ');
      const std::string pid = text.substr(0, space);
      const bool has_pid = !pid.empty() && pid.find_first_not_of("0123456789") == std::string::npos;
      const std::string who =
          space != std::string::npos && text.substr(space + 1).starts_with("sirl ")
              ? text.substr(space + 1)
              : std::string("another sirl process");
      throw FileBusy(file + " is in use by " + who + (has_pid ? " (pid " + pid + ")" : "") + "; " +
                     advice);
    }
    throw std::runtime_error(path_ + ": cannot lock: " + std::strerror(err));
  }
  const std::string me = std::to_string(::getpid()) + " " + holder;
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, me.data(), me.size(), 0) < 0) {
    // the lock holds without the note; a second writer just cannot name us
  }
}

FileLock::~FileLock() {
  ::close(fd_);
}

}  // namespace sirl
