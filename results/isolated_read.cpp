#include "results/isolated_read.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>

#include "results/h5.h"

// Under a sanitizer or libFuzzer (the asan preset), their death callback would report the
// child's crash as the process's own: the child clears it. Absent otherwise (a weak symbol).
extern "C" void __sanitizer_set_death_callback(void (*)(void)) __attribute__((weak));
// The sanitizers' allocator hooks and size query (weak: absent outside a sanitizer build).
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*)(const volatile void*, size_t),
                                                         void (*)(const volatile void*))
    __attribute__((weak));
extern "C" size_t __sanitizer_get_allocated_size(const volatile void*) __attribute__((weak));

#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
#define SIRL_SANITIZED_BUILD 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define SIRL_SANITIZED_BUILD 1
#endif

namespace sirl {

namespace {

// Exit codes of the child besides 0 (read), 3 (threw; its message follows) and 4 (threw
// something else): it needed more memory than its budget allows.
constexpr int kOverMemory = 5;

// What the sandboxed read of a file of `bytes` may use. Every value a file holds is stored in
// it, and deflate (the only filter the engine writes) expands at most 1032-fold, but a crafted
// file can claim far more than it stores: a variable-length string's reference carries its own
// 32-bit length, and HDF5 allocates and clears that many bytes before it finds the heap object
// shorter; a dataspace can claim 2^64 elements of never-written storage. Such claims are refused
// here, once, for every reader: memory of 256 MiB plus 64 times the file (quick's results file
// holds 1.15 times its size in values, its most compressed dataset 12.6 times its storage) and CPU
// time of 30 s plus 1 s per 8 MiB (reading runs at hundreds of MB/s), so a crafted file is one
// error line, never a machine out of memory or a hung command.
struct ReadBudget {
  size_t memory_bytes;
  rlim_t cpu_seconds;
};

ReadBudget budget_for(const std::string& path) {
  struct stat st {};
  const size_t bytes = ::stat(path.c_str(), &st) == 0 && st.st_size > 0 ? size_t(st.st_size) : 0;
  const size_t cap = size_t(1) << 46;  // no overflow below
  const size_t file = std::min(bytes, cap / 128);
  return {(size_t(256) << 20) + 64 * file, rlim_t(30 + file / (size_t(8) << 20))};
}

// Bytes allocated by the child and not freed, counted by the sanitizer hooks (their allocator
// maps terabytes of shadow memory, so an address-space limit cannot bound it). Signed: freeing
// what the parent had allocated before the fork takes it below zero.
std::atomic<int64_t> g_live_bytes{0};
int64_t g_memory_budget = 0;

void count_malloc(const volatile void*, size_t size) {
  const int64_t n = int64_t(std::min<size_t>(size, size_t(1) << 62));
  if (g_live_bytes.fetch_add(n, std::memory_order_relaxed) + n > g_memory_budget)
    ::_exit(kOverMemory);
}
void count_free(const volatile void* p) {
  if (p)
    g_live_bytes.fetch_sub(int64_t(__sanitizer_get_allocated_size(p)), std::memory_order_relaxed);
}

// This process's address space now, in bytes (the child starts as a copy of it).
size_t address_space_bytes() {
  unsigned long pages = 0;
  if (FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%lu", &pages) != 1) pages = 0;
    std::fclose(f);
  }
  return size_t(pages) * size_t(::sysconf(_SC_PAGESIZE));
}

// In the child: bounds its CPU time and the memory its read may take (see ReadBudget).
void limit_child(const ReadBudget& budget, size_t address_space) {
  const rlimit cpu{budget.cpu_seconds, budget.cpu_seconds + 1};
  ::setrlimit(RLIMIT_CPU, &cpu);  // SIGXCPU at the soft limit, SIGKILL at the hard one
#ifdef SIRL_SANITIZED_BUILD
  (void)address_space;
  if (&__sanitizer_install_malloc_and_free_hooks && &__sanitizer_get_allocated_size) {
    g_memory_budget = int64_t(budget.memory_bytes);
    __sanitizer_install_malloc_and_free_hooks(count_malloc, count_free);
  }
#else
  (void)count_malloc;
  (void)count_free;
  if (address_space == 0) return;  // unknown: a limit below what is mapped would refuse any file
  const rlim_t limit = rlim_t(address_space + budget.memory_bytes);
  const rlimit as{limit, limit};
  ::setrlimit(RLIMIT_AS, &as);  // an allocation beyond it fails: malloc returns null, new throws
#endif
}

}  // namespace

void read_in_child_first(const std::string& path, const std::function<void()>& read) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw H5Error(path + ": cannot start a sandboxed read: " + std::strerror(errno));
  std::fflush(nullptr);  // nothing buffered is written twice by the child
  const ReadBudget budget = budget_for(path);
  const size_t address_space = address_space_bytes();
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
    limit_child(budget, address_space);
    int rc = 0;
    try {
      read();
    } catch (const std::bad_alloc&) {
      rc = kOverMemory;
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
  rusage usage{};
  while (::wait4(pid, &status, 0, &usage) < 0 && errno == EINTR) {
  }
  const double cpu = double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
                     1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 3) throw H5Error(msg);
  if (WIFEXITED(status) && WEXITSTATUS(status) == kOverMemory)
    throw H5Error(path + ": its HDF5 structures claim more data than the file can hold (reading " +
                  "them needed more than " + std::to_string(budget.memory_bytes >> 20) +
                  " MiB in a sandboxed read); the file was damaged or crafted after its " +
                  "checksum was computed, and cannot be read");
  if (WIFSIGNALED(status) && (WTERMSIG(status) == SIGXCPU ||
                              (WTERMSIG(status) == SIGKILL && cpu >= double(budget.cpu_seconds))))
    throw H5Error(path + ": reading its HDF5 structures did not end within " +
                  std::to_string(budget.cpu_seconds) +
                  " s of CPU time in a sandboxed read, far more than a file of its size needs; "
                  "the file was damaged or crafted after its checksum was computed, and cannot "
                  "be read");
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
