#include "results/file_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace sirl {

namespace {
// What a sirl lock file holds: "<pid> sirl <command>" (or nothing, when its writer died between
// creating and writing it).
bool is_sirl_lock_text(const std::string& text) {
  if (text.empty()) return true;
  const size_t space = text.find(' ');
  return space != std::string::npos && space > 0 && text.find_first_not_of("0123456789") == space &&
         text.substr(space + 1).starts_with("sirl ");
}

// The text as one printable line (a lock file's bytes are not ours to print: no escapes).
std::string printable(const std::string& text) {
  std::string out;
  for (char c : text.substr(0, 120)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
  return out;
}
}  // namespace

// One attempt: opens (creating) path_, checks it is a sirl lock, takes the flock. Returns false
// when the file it locked is no longer at path_ (its holder removed it meanwhile): try again.
bool FileLock::try_lock(const std::string& file, const std::string& holder,
                        const std::string& advice) {
  // Created exclusively; an existing file is opened only to check that it is a sirl lock (a
  // Cargo.lock or yarn.lock beside `sirl merge Cargo …` is the user's and is never truncated).
  // O_NOFOLLOW: a link planted at OUT.lock must not make us write our pid into its target.
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0644);
  const bool created = fd_ >= 0;
  if (!created && errno == EEXIST) {
    fd_ = ::open(path_.c_str(), O_RDWR | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
    if (fd_ < 0 && errno == ENOENT) return false;  // its holder removed it meanwhile
  }
  if (fd_ < 0 && errno == ELOOP)
    throw FileBusy(path_ +
                   " is a symbolic link; sirl creates this file itself and does "
                   "not write through links: remove it");
  if (fd_ < 0)
    throw std::runtime_error(path_ + ": cannot create the lock file: " + std::strerror(errno));
  char buf[256] = {};
  const ssize_t n = ::pread(fd_, buf, sizeof buf - 1, 0);
  const std::string text = n > 0 ? std::string(buf, size_t(n)) : std::string();
  if (!created) {
    struct stat st {};
    if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode) || !is_sirl_lock_text(text)) {
      ::close(fd_);
      fd_ = -1;
      // Exit 2 as a held lock: the output's name is taken, by something that is not ours.
      throw FileBusy(path_ +
                     " exists and is not a sirl lock file (it is not \"<pid> "
                     "sirl <command>\"); sirl never overwrites it: choose another "
                     "output name, or remove it if it is a stale lock");
    }
  }
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    if (err == EWOULDBLOCK) {
      // The holder wrote "<pid> <command>": name what actually holds it, not what we are.
      const size_t space = text.find(' ');
      const std::string pid = text.substr(0, space);
      const bool has_pid = !pid.empty() && pid.find_first_not_of("0123456789") == std::string::npos;
      const std::string who =
          space != std::string::npos && text.substr(space + 1).starts_with("sirl ")
              ? printable(text.substr(space + 1))
              : std::string("another sirl process");
      throw FileBusy(file + " is in use by " + who +
                     (has_pid ? " (pid " + printable(pid) + ")" : "") + "; " + advice);
    }
    throw std::runtime_error(path_ + ": cannot lock: " + std::strerror(err));
  }
  // Locked; but the holder may have removed the file between our open and our flock, and a third
  // process may have created a new one at the name: only the file at path_ counts.
  struct stat mine {
  }, named{};
  if (::fstat(fd_, &mine) != 0 || ::lstat(path_.c_str(), &named) != 0 ||
      mine.st_dev != named.st_dev || mine.st_ino != named.st_ino) {
    ::close(fd_);
    fd_ = -1;
    return false;
  }
  const std::string me = std::to_string(::getpid()) + " " + holder;
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, me.data(), me.size(), 0) < 0) {
    // the lock holds without the note; a second writer just cannot name us
  }
  return true;
}

FileLock::FileLock(const std::string& file, const std::string& holder, const std::string& advice)
    : path_(file + ".lock") {
  // Each retry follows a holder's removal of the file; a few in a row mean something else keeps
  // replacing it.
  for (int attempt = 0; attempt < 100; ++attempt)
    if (try_lock(file, holder, advice)) return;
  throw std::runtime_error(path_ +
                           ": the lock file keeps being replaced; is another program "
                           "removing it?");
}

FileLock::~FileLock() {
  if (fd_ < 0) return;
  // Removed while still held (a taker that opened it before checks that it is still at the path,
  // and starts over), and only when the path still names our file.
  struct stat mine {
  }, named{};
  if (::fstat(fd_, &mine) == 0 && ::lstat(path_.c_str(), &named) == 0 &&
      mine.st_dev == named.st_dev && mine.st_ino == named.st_ino)
    ::unlink(path_.c_str());
  ::close(fd_);
}

}  // namespace sirl
