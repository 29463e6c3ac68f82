#include "results/task_store.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string_view>

#include "kernels/rng.h"
#include "results/durable.h"
#include "results/h5.h"

namespace sirl {

namespace fs = std::filesystem;

namespace {

// Every commit starts with a userblock HDF5 leaves alone, holding what is needed to trust the
// file before the HDF5 library reads a byte of it (a corrupted HDF5 file can crash the library):
//   "SIRLTASK2\n" <file_digest of bytes [kFrameBytes, end), 32 hex> "\n" <task key> "\n" NUL…
// Commits of engines 0.3.0–0.7.0 ("SIRLTASK1\n", a 16-digit FNV checksum) and of 0.2.0 (no
// userblock: they start with HDF5's signature) are still read.
constexpr uint64_t kFrameBytes = 1024;
constexpr std::string_view kFrameMagic = "SIRLTASK2\n", kFrameMagicV1 = "SIRLTASK1\n";
constexpr std::string_view kHdf5Signature = "\x89HDF\r\n\x1a\n";

struct Frame {
  bool framed = false;              // false: a commit of engine 0.2.0 (plain HDF5)
  std::string checksum, key, head;  // checksum: 32 hex (SIRLTASK2) or 16 (SIRLTASK1)
};

std::string frame_text(std::string_view magic, const std::string& checksum,
                       const std::string& key) {
  std::string head = std::string(magic) + checksum + "\n" + key + "\n";
  if (head.size() > kFrameBytes) throw H5Error("task key too long for a commit: " + key);
  head.resize(kFrameBytes, '\0');
  return head;
}

// Whether p is a regular file (not a link, FIFO, device or folder): the only thing the store
// writes, and the only thing it opens (a FIFO at a commit's name would block a reader forever).
bool regular_file(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(fs::symlink_status(p, ec));
}

// Throws H5Error if the file is neither a framed commit nor plain HDF5.
Frame read_frame(const fs::path& p) {
  if (!regular_file(p)) throw H5Error(p.string() + ": not a task commit (not a regular file)");
  std::ifstream in(p, std::ios::binary);
  std::string head(kFrameBytes, '\0');
  in.read(head.data(), std::streamsize(head.size()));
  head.resize(size_t(in.gcount()));
  Frame f;
  if (head.starts_with(kHdf5Signature)) return f;
  const bool v2 = head.starts_with(kFrameMagic), v1 = head.starts_with(kFrameMagicV1);
  const size_t digits = v2 ? 32 : 16, sum_end = kFrameMagic.size() + digits,
               key_end = head.find('\n', sum_end + 1);
  if ((!v1 && !v2) || head.size() < kFrameBytes || head[sum_end] != '\n' ||
      key_end == std::string::npos)
    throw H5Error(p.string() + ": not a task commit (corrupted or truncated)");
  f.framed = true;
  f.checksum = head.substr(kFrameMagic.size(), digits);
  f.key = head.substr(sum_end + 1, key_end - sum_end - 1);
  // Every byte of the frame is accounted for: a flipped bit in its padding is damage too.
  if (frame_text(v2 ? kFrameMagic : kFrameMagicV1, f.checksum, f.key) != head)
    throw H5Error(p.string() + ": not a task commit (corrupted frame)");
  return f;
}

// The digest a frame of this kind records (SIRLTASK1: the old FNV checksum).
std::string frame_checksum(const fs::path& p, size_t digits) {
  try {
    return digits == 32 ? file_digest(p.string(), kFrameBytes)
                        : hex64(file_checksum(p.string(), kFrameBytes));
  } catch (const std::runtime_error& e) {
    throw H5Error(e.what());
  }
}

// Fills the userblock of a closed commit file for `key`.
void write_frame(const fs::path& p, const std::string& key) {
  try {
    overwrite_head(p.string(), frame_text(kFrameMagic, frame_checksum(p, 32), key));
  } catch (const std::runtime_error& e) {
    throw H5Error(e.what());
  }
}

// The record committed in `p` under `id` for task `key`, verified before HDF5 opens the file
// (framed commits) and against the record checksum after. A corrupted file is refused naming the
// task (and removed when `remove_if_corrupt`, so that a rerun computes the task again).
TaskRecord read_commit(const fs::path& p, const std::string& id, const std::string& key,
                       bool remove_if_corrupt) {
  auto corrupted = [&](const std::string& why) {
    std::error_code ec;
    if (remove_if_corrupt) fs::remove(p, ec);
    return H5Error("task " + key + ": its committed file " + p.string() + " is corrupted (" + why +
                   ")" +
                   (remove_if_corrupt ? "; it was removed: rerun to compute the task again" : ""));
  };
  Frame frame;
  try {
    frame = read_frame(p);
  } catch (const H5Error&) {
    throw corrupted("no commit header");
  }
  if (frame.framed) {
    if (frame.key != id) throw H5Error(p.string() + ": holds " + frame.key + ", not " + id);
    if (frame_checksum(p, frame.checksum.size()) != frame.checksum)
      throw corrupted("checksum mismatch");
  }
  H5File f = H5File::open_read(p.string());
  TaskRecord r = read_record(f, "/r");
  r.text.erase("record_checksum");  // written beside the record, not part of it
  if (r.key != key) throw H5Error(p.string() + ": holds task " + r.key + ", not " + key);
  if (f.has_attr("/r", "record_checksum")) {
    const std::string want = f.attr_string("/r", "record_checksum");
    if (want != (want.size() == 16 ? record_checksum_fnv(r) : record_checksum(r)))
      throw corrupted("record checksum mismatch");
  }
  return r;
}

std::string this_host() {
  char buf[256] = {};
  gethostname(buf, sizeof buf - 1);
  return buf;
}

// A commit's temporary file names its writer, "<final>.<host>.<pid>.tmp", so that a process
// opening a shared store removes only what a dead process of this host left behind, never the
// half-written commit of a live one.
std::string tmp_suffix() {
  static const std::string s = [] {
    std::string t = ".";
    t.append(this_host()).append(".").append(std::to_string(::getpid())).append(".tmp");
    return t;
  }();
  return s;
}

// Whether the file at `p` begins like something the store writes: a commit's frame, its
// zero-filled userblock before the frame is written, an old engine's HDF5 commit, or nothing (a
// writer that died before its first byte).
bool store_bytes(const fs::path& p) {
  if (!regular_file(p)) return false;
  std::ifstream in(p, std::ios::binary);
  char head[8] = {};
  in.read(head, sizeof head);
  const std::string_view h(head, size_t(in.gcount()));
  return h.empty() || h == "SIRLTASK" || h == std::string_view("\x89HDF\r\n\x1a\n", 8) ||
         h == std::string_view("\0\0\0\0\0\0\0\0", 8);
}

// Whether a temporary file of the store may be removed: its writer, named in the file name, is a
// dead process of this host, and its bytes begin as the store's do. A name that only looks like
// ours (no host, a pid no process can have), bytes that are not the store's (a user's notes), and
// an engine before 0.10.0's "<final>.tmp" (no writer named: nothing says it is ours) are left
// alone.
bool abandoned_tmp(const fs::path& p, const std::string& name) {
  if (name.size() == 23) return false;                       // "<final>.tmp"
  const std::string stem = name.substr(0, name.size() - 4);  // without ".tmp"
  const size_t dot_pid = stem.rfind('.');
  if (dot_pid == std::string::npos) return false;
  const std::string pid = stem.substr(dot_pid + 1), rest = stem.substr(0, dot_pid);
  const size_t dot_host = rest.rfind('.');
  if (pid.empty() || pid.size() > 9 || pid.find_first_not_of("0123456789") != std::string::npos ||
      dot_host == std::string::npos || !rest.substr(0, dot_host).ends_with(".h5"))
    return false;                                              // not a name this store writes
  if (rest.substr(dot_host + 1) != this_host()) return false;  // another host's: not ours to judge
  return ::kill(pid_t(std::stol(pid)), 0) != 0 && errno == ESRCH && store_bytes(p);
}

// The id a commit file is filed under (its frame's, or an engine 0.2.0 file's task key).
std::string commit_id(const fs::path& p) {
  const Frame frame = read_frame(p);  // reads no HDF5 (and is fast)
  if (frame.framed) return frame.key;
  H5File f = H5File::open_read(p.string());
  return f.attr_string("/r", "task_key");
}

}  // namespace

bool TaskStore::is_commit_name(const std::string& name) {
  return name.size() == 19 && name.ends_with(".h5") &&
         name.find_first_not_of("0123456789abcdef") == 16;
}

bool TaskStore::is_temporary_name(const std::string& name) {
  return name.size() >= 23 && name.ends_with(".tmp") && is_commit_name(name.substr(0, 19)) &&
         name[19] == '.';
}

TaskStore::TaskStore(fs::path dir) : dir_(std::move(dir)) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) throw H5Error(dir_.string() + ": cannot create the task directory: " + ec.message());
  for (const auto& e : fs::directory_iterator(dir_)) {
    const auto name = e.path().filename().string();
    if (!regular_file(e.path())) continue;  // links, FIFOs, folders: never opened, never removed
    if (is_temporary_name(name)) {
      if (abandoned_tmp(e.path(), name)) fs::remove(e.path(), ec);
      continue;
    }
    if (!is_commit_name(name)) continue;  // not the store's: left alone
    try {
      index_[commit_id(e.path())] = e.path();
    } catch (const H5Error&) {
      // A file with a commit's name that does not read as one is left alone and not indexed:
      // its bytes may be anyone's (a damaged commit of ours is recomputed when its task is next
      // needed, and its new commit replaces it under the same name).
    }
  }
}

std::vector<std::string> TaskStore::ids_in(const fs::path& dir) {
  std::vector<std::string> ids;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return ids;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (!regular_file(e.path()) || !is_commit_name(e.path().filename().string())) continue;
    try {
      ids.push_back(commit_id(e.path()));
    } catch (const H5Error&) {
      // a damaged file holds nothing to count; the next run that opens the store removes it
    }
  }
  return ids;
}

fs::path TaskStore::file_for(const fs::path& dir, const std::string& id) {
  char name[32];
  std::snprintf(name, sizeof name, "%016llx.h5",
                static_cast<unsigned long long>(seed_from_key(id, 0)));
  return dir / name;
}

TaskRecord TaskStore::load_from(const fs::path& dir, const std::string& id,
                                const std::string& key) {
  const fs::path p = file_for(dir, id);
  if (!fs::exists(p)) throw H5Error(dir.string() + ": no committed task " + key);
  return read_commit(p, id, key, false);  // another process's file: never removed from here
}

bool TaskStore::has(const std::string& id) const {
  std::lock_guard lock(mu_);
  if (index_.count(id)) return true;
  const fs::path p = file_for(dir_, id);
  std::error_code ec;
  if (!fs::exists(p, ec)) return false;
  try {
    if (commit_id(p) != id) return false;  // another id's file under the same 64-bit name
  } catch (const H5Error&) {
    return false;
  }
  index_[id] = p;
  return true;
}

std::vector<std::string> TaskStore::keys() const {
  std::lock_guard lock(mu_);
  std::vector<std::string> k;
  for (const auto& [key, p] : index_) k.push_back(key);
  return k;
}

void TaskStore::commit(const TaskRecord& r, const std::string& id) {
  const fs::path final = file_for(dir_, id);
  const fs::path tmp = final.string() + tmp_suffix();
  try {
    {
      H5File f = H5File::create(tmp.string(), kFrameBytes);
      write_record(f, "/r", r);
      f.set_attr("/r", "record_checksum", record_checksum(r));
      f.flush();  // a full disk shows here, not in a destructor
    }             // closed: every byte handed to the OS
    write_frame(tmp, id);
  } catch (const std::exception& e) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw H5Error("cannot save task " + r.key + ": " + e.what());
  }
  fsync_path(tmp.string());
  // With the crash hook on, commits are serialised up to the hook, so that exactly k land
  // before the process ends (two threads renaming at once made k + 1); off, this locks nothing.
  const std::unique_lock<std::mutex> hook = crash_point_serialise();
  std::error_code ec;
  fs::rename(tmp, final, ec);
  if (ec) throw H5Error(final.string() + ": cannot commit task " + r.key + ": " + ec.message());
  fsync_path(dir_.string());
  {
    std::lock_guard lock(mu_);
    index_[id] = final;
  }
  crash_point_after_commit();
}

void TaskStore::remove(const std::string& id) {
  std::lock_guard lock(mu_);
  const auto it = index_.find(id);
  if (it == index_.end()) return;
  std::error_code ec;
  fs::remove(it->second, ec);
  index_.erase(it);
}

bool TaskStore::empty() const {
  std::lock_guard lock(mu_);
  return index_.empty();
}

namespace {
long crash_after_commits() {
  static const long k = [] {
    const char* v = std::getenv("SIRL_CRASH_AFTER_COMMITS");
    return v ? std::strtol(v, nullptr, 10) : 0L;
  }();
  return k;
}
}  // namespace

std::unique_lock<std::mutex> crash_point_serialise() {
  static std::mutex mu;
  return crash_after_commits() > 0 ? std::unique_lock<std::mutex>(mu)
                                   : std::unique_lock<std::mutex>();
}

void crash_point_after_commit() {
  // Crash-point injection for tests: SIRL_CRASH_AFTER_COMMITS=k ends the process, as kill -9
  // would (no destructors, no flush), right after the k-th durable commit of this process.
  static std::atomic<long> commits{0};
  const long k = crash_after_commits();
  if (k > 0 && ++commits == k) std::_Exit(137);
}

TaskRecord TaskStore::load(const std::string& id, const std::string& key) const {
  fs::path p;
  {
    std::lock_guard lock(mu_);
    auto it = index_.find(id);
    if (it == index_.end()) throw H5Error(dir_.string() + ": no committed task " + key);
    p = it->second;
  }
  return read_commit(p, id, key, true);
}

std::string TaskStore::verify(const std::string& id, const std::string& key) const {
  fs::path p;
  {
    std::lock_guard lock(mu_);
    auto it = index_.find(id);
    if (it == index_.end()) return "task " + key + ": not in " + dir_.string();
    p = it->second;
  }
  std::string why;
  try {
    const Frame frame = read_frame(p);
    if (frame.framed && frame.key != id)
      why = "it holds " + frame.key;
    else if (frame.framed && frame_checksum(p, frame.checksum.size()) != frame.checksum)
      why = "checksum mismatch";
  } catch (const H5Error& e) {
    why = e.what();
  }
  if (why.empty()) return "";
  std::error_code ec;
  fs::remove(p, ec);
  std::lock_guard lock(mu_);
  index_.erase(id);
  return "task " + key + ": its committed file " + p.string() + " is corrupted (" + why + ")";
}

uint64_t TaskStore::bytes(const std::string& id) const {
  std::lock_guard lock(mu_);
  auto it = index_.find(id);
  std::error_code ec;
  const uint64_t n = it == index_.end() ? 0 : fs::file_size(it->second, ec);
  return ec ? 0 : n;
}

std::string record_checksum(const TaskRecord& r) {
  // XXH3-128 over the record's canonical serialisation (every key, number and array byte).
  const std::string bytes = serialize(r);
  return bytes_digest(bytes.data(), bytes.size());
}

std::string record_checksum_fnv(const TaskRecord& r) {
  const std::string bytes = serialize(r);
  uint64_t h = 0xCBF29CE484222325ull;
  for (unsigned char c : bytes) h = (h ^ c) * 0x100000001B3ull;
  return hex64(h);
}

void TaskStore::write_manifest(const std::string& name, const std::string& text) {
  const fs::path final = dir_ / name, tmp = dir_ / (name + ".tmp");
  {
    std::ofstream out(tmp);
    out << text;
    if (!out) throw H5Error(tmp.string() + ": cannot write");
  }
  fsync_path(tmp.string());
  fs::rename(tmp, final);
}

std::string TaskStore::read_manifest(const std::string& name) const {
  std::ifstream in(dir_ / name);
  if (!in) return "";
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace sirl
