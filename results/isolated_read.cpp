#include "results/isolated_read.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <exception>

#include "results/h5.h"

// Under a sanitizer or libFuzzer (the asan preset), their death callback would report the
// child's crash as the process's own: the child clears it. Absent otherwise (a weak symbol).
extern "C" void __sanitizer_set_death_callback(void (*)(void)) __attribute__((weak));

namespace sirl {

void read_in_child_first(const std::string& path, const std::function<void()>& read) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw H5Error(path + ": cannot start a sandboxed read: " + std::strerror(errno));
  std::fflush(nullptr);  // nothing buffered is written twice by the child
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int e = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw H5Error(path + ": cannot start a sandboxed read: " + std::strerror(e));
  }
  if (pid == 0) {
    ::close(fds[0]);
    // A crash's own report (a sanitizer's, HDF5's) is not the user's line: the parent says it.
    if (const int null = ::open("/dev/null", O_WRONLY); null >= 0) ::dup2(null, 2);
    // A crash here is the expected end of a hostile file, not a bug of this process: the
    // default action (die by the signal), which the parent reads, rather than any handler
    // installed to report crashes.
    for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) std::signal(sig, SIG_DFL);
    if (&__sanitizer_set_death_callback) __sanitizer_set_death_callback(nullptr);
    int rc = 0;
    try {
      read();
    } catch (const std::exception& e) {
      const std::string msg = e.what();
      [[maybe_unused]] const ssize_t n = ::write(fds[1], msg.data(), msg.size());
      rc = 3;
    } catch (...) {
      rc = 4;
    }
    ::_exit(rc);  // no destructors, no atexit handlers, no flushing of the parent's buffers
  }
  ::close(fds[1]);
  std::string msg;
  char buf[4096];
  for (ssize_t n; (n = ::read(fds[0], buf, sizeof buf)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    msg.append(buf, size_t(n));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 3) throw H5Error(msg);
  const std::string how = WIFSIGNALED(status)
                              ? std::string("signal ") + std::to_string(WTERMSIG(status)) + " (" +
                                    strsignal(WTERMSIG(status)) + ")"
                              : "exit " + std::to_string(WEXITSTATUS(status));
  throw H5Error(path +
                ": its HDF5 structures are malformed (reading them crashed the HDF5 "
                "library in a sandboxed read: " +
                how +
                "); the file was damaged or crafted after its checksum was computed, and "
                "cannot be read");
}

}  // namespace sirl
