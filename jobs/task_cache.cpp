#include "jobs/task_cache.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "results/durable.h"
#include "results/h5.h"

namespace sirl {

namespace fs = std::filesystem;

namespace {

// Whether fd is a regular file (a FIFO or device planted under a lock's name is not a lock: reading
// one would wait forever for a writer).
bool is_regular(int fd) {
  struct stat st {};
  return ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode);
}

// Opens (creating, unless !create) a lock file. O_NOFOLLOW: a planted link must not make a run
// lock (or gc delete) its target; O_NONBLOCK: opening a planted FIFO must not hang. Returns -1
// when !create and the file is absent.
int open_lock_file(const fs::path& p, bool create = true) {
  const int fd = ::open(
      p.c_str(), O_RDWR | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK | (create ? O_CREAT : 0), 0644);
  if (fd < 0 && !create && errno == ENOENT) return -1;
  if (fd < 0)
    throw std::runtime_error(p.string() + ": cannot open the lock file: " + std::strerror(errno));
  if (!is_regular(fd)) {
    ::close(fd);
    throw std::runtime_error(p.string() +
                             ": is not a regular file, so not a sirl lock; remove it if it is "
                             "not yours");
  }
  return fd;
}

// Whether another process holds an flock on `p` (false when the file is absent or is no regular
// file, which no sirl process locks).
bool held_elsewhere(const fs::path& p) {
  const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
  if (fd < 0) return false;
  const bool held = is_regular(fd) && ::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  ::close(fd);
  return held;
}

bool is_digest(const std::string& s) {
  return s.size() == 32 && s.find_first_not_of("0123456789abcdef") == std::string::npos;
}

// Whether a file in runs/ is a needs file a run wrote: named "<host>.<pid>" (a pid of at most
// 9 digits) and holding task digests, one per line. Anything else there is not ours.
bool is_needs_file(const fs::path& p) {
  const std::string name = p.filename().string();
  const size_t dot = name.rfind('.');
  if (dot == std::string::npos || dot == 0 || name.size() - dot - 1 > 9 || dot + 1 == name.size() ||
      name.find_first_not_of("0123456789", dot + 1) != std::string::npos)
    return false;
  std::ifstream in(p);
  for (std::string line; std::getline(in, line);)
    if (!is_digest(line)) return false;
  return true;
}

// Whether a file in locks/ is a task lock: "<digest>.lock", empty (a claim never writes it).
bool is_task_lock(const fs::directory_entry& e) {
  const std::string name = e.path().filename().string();
  std::error_code ec;
  return name.size() == 37 && name.ends_with(".lock") && is_digest(name.substr(0, 32)) &&
         e.file_size(ec) == 0 && !ec;
}

std::string host_name() {
  char buf[256] = {};
  gethostname(buf, sizeof buf - 1);
  return buf;
}

// Takes the cache's gate (gc.lock, see task_cache.h) in mode `how` (LOCK_SH or LOCK_EX),
// waiting for it, and saying so on stderr first (the holder may be a gc sweeping, a run starting,
// or a process someone stopped with ^Z); returns its descriptor (closing it releases the lock).
int take_gate(const fs::path& dir, int how, bool create = true) {
  if (create) {
    std::error_code ec;
    fs::create_directories(dir, ec);
  }
  const int fd = open_lock_file(dir / "gc.lock", create);
  if (fd < 0) return fd;
  if (::flock(fd, how | LOCK_NB) == 0) return fd;
  if (errno == EWOULDBLOCK)
    std::fprintf(stderr, "sirl: waiting for %s: %s\n", (dir / "gc.lock").c_str(),
                 how == LOCK_EX
                     ? "a run is opening this cache (or is stopped while opening it)"
                     : "`sirl gc` is sweeping this cache (or is stopped while sweeping)");
  while (::flock(fd, how) != 0)
    if (errno != EINTR) {
      const int err = errno;
      ::close(fd);
      throw std::runtime_error((dir / "gc.lock").string() + ": cannot lock: " + std::strerror(err));
    }
  return fd;
}

}  // namespace

TaskCache::TaskCache(fs::path dir) : gate_fd_(take_gate(dir, LOCK_SH)), store_(std::move(dir)) {
  std::error_code ec;
  for (const char* sub : {"locks", "runs"}) {
    refuse_symlink((store_.dir() / sub).string());
    fs::create_directories(store_.dir() / sub, ec);
    if (ec) throw H5Error((store_.dir() / sub).string() + ": cannot create: " + ec.message());
  }
}

TaskCache::~TaskCache() {
  if (gate_fd_ >= 0) ::close(gate_fd_);
  if (needs_fd_ >= 0) {
    std::error_code ec;
    fs::remove(needs_path_, ec);
    ::close(needs_fd_);
  }
}

std::string TaskCache::id(const std::string& digest, const std::string& cpu_class) {
  return digest + "-" + bytes_digest(cpu_class.data(), cpu_class.size()).substr(0, 8);
}

std::string TaskCache::find(const std::string& digest, const std::string& cpu_class,
                            bool any_class) const {
  const std::string mine = id(digest, cpu_class);
  if (store_.has(mine)) return mine;
  if (!any_class) return "";
  for (const std::string& k : store_.keys())
    if (k.starts_with(digest + "-")) return k;
  return "";
}

void TaskCache::register_needs(const std::vector<std::string>& digests) {
  needs_path_ = store_.dir() / "runs" / (host_name() + "." + std::to_string(::getpid()));
  needs_fd_ = open_lock_file(needs_path_);
  if (::flock(needs_fd_, LOCK_EX | LOCK_NB) != 0)
    throw std::runtime_error(needs_path_.string() + ": cannot lock: " + std::strerror(errno));
  std::string text;
  for (const auto& d : digests) text += d + "\n";
  if (::ftruncate(needs_fd_, 0) != 0 ||
      ::pwrite(needs_fd_, text.data(), text.size(), 0) != ssize_t(text.size()))
    throw std::runtime_error(needs_path_.string() + ": cannot write: " + std::strerror(errno));
  ::close(gate_fd_);  // declared: a sweep from now on keeps them
  gate_fd_ = -1;
}

TaskCache::Claim::~Claim() {
  if (fd_ >= 0) ::close(fd_);  // closing releases the flock
}

TaskCache::Claim TaskCache::claim(const std::string& digest,
                                  const std::function<void()>& waiting) const {
  const int fd = open_lock_file(store_.dir() / "locks" / (digest + ".lock"));
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return Claim(fd);
  if (errno != EWOULDBLOCK) {
    const int err = errno;
    ::close(fd);
    throw std::runtime_error("cannot lock task " + digest + ": " + std::strerror(err));
  }
  if (waiting) waiting();
  while (::flock(fd, LOCK_EX) != 0)
    if (errno != EINTR) {
      const int err = errno;
      ::close(fd);
      throw std::runtime_error("cannot lock task " + digest + ": " + std::strerror(err));
    }
  return Claim(fd);
}

GcSummary collect_garbage(const fs::path& dir, const std::set<std::string>& keep, bool dry_run) {
  if (!fs::is_directory(dir)) throw std::runtime_error(dir.string() + ": no such cache folder");
  // Every cache has its gate (a TaskCache creates it): a folder without one is not a cache, and
  // gc neither sweeps it nor leaves a gc.lock in it.
  if (!fs::is_regular_file(fs::symlink_status(dir / "gc.lock")))
    throw std::runtime_error(dir.string() +
                             " is not a task cache (it has no gc.lock): a cache is the folder "
                             "of `sirl run --cache DIR`, or OUT.tasks beside a results file");
  // Exclusive: no run is between listing the cache and declaring its needs while this sweeps.
  // (A dry run of a folder it may not write proceeds without it: it removes nothing.)
  struct Gate {
    int fd = -1;
    ~Gate() {
      if (fd >= 0) ::close(fd);
    }
  } gate;
  try {
    gate.fd = take_gate(dir, LOCK_EX, false);
  } catch (const std::runtime_error&) {
    if (!dry_run) throw;
  }
  std::set<std::string> needed = keep;
  std::set<std::string> held;  // needed by a running process
  std::error_code ec;
  if (fs::is_directory(dir / "runs"))
    for (const auto& e : fs::directory_iterator(dir / "runs")) {
      if (e.is_symlink() || !e.is_regular_file() || !is_needs_file(e.path()))
        continue;                       // no run writes anything else
      if (!held_elsewhere(e.path())) {  // its process ended without removing it
        if (!dry_run) fs::remove(e.path(), ec);
        continue;
      }
      std::ifstream in(e.path());  // a regular file, held by a live run: its needs, one a line
      for (std::string line; std::getline(in, line);)
        if (is_digest(line)) held.insert(line);
    }
  auto computing = [&](const std::string& digest) {
    return held_elsewhere(dir / "locks" / (digest + ".lock"));
  };
  GcSummary s;
  auto sweep = [&](const fs::path& folder) {
    for (const std::string& id : TaskStore::ids_in(folder)) {
      const std::string digest = id.substr(0, id.find('-'));
      const fs::path file = TaskStore::file_for(folder, id);
      const uint64_t bytes = fs::file_size(file, ec);
      if (is_digest(digest) && (needed.count(digest) || held.count(digest) || computing(digest))) {
        ++s.kept;
        s.kept_bytes += ec ? 0 : bytes;
        if (!needed.count(digest)) ++s.held;
        continue;
      }
      ++s.removed;
      s.removed_bytes += ec ? 0 : bytes;
      if (!dry_run) fs::remove(file, ec);
    }
  };
  sweep(dir);
  if (!fs::is_symlink(dir / "checkpoints")) sweep(dir / "checkpoints");  // links: never followed
  if (!dry_run && fs::is_directory(dir / "locks"))
    for (const auto& e : fs::directory_iterator(dir / "locks")) {
      const std::string name = e.path().filename().string();
      const std::string digest = name.substr(0, name.find('.'));
      if (e.is_symlink() || !e.is_regular_file() || !is_task_lock(e) || needed.count(digest) ||
          held.count(digest))
        continue;
      const int fd = ::open(e.path().c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
      if (fd < 0) continue;
      if (is_regular(fd) && ::flock(fd, LOCK_EX | LOCK_NB) == 0) fs::remove(e.path(), ec);
      ::close(fd);
    }
  return s;
}

}  // namespace sirl
