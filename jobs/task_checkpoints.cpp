#include "jobs/task_checkpoints.h"

#include <chrono>
#include <cstdio>
#include <stdexcept>

#include "jobs/stop_request.h"
#include "results/h5.h"

namespace sirl {

namespace {

using Clock = std::chrono::steady_clock;

class FileCheckpointer : public Checkpointer {
 public:
  FileCheckpointer(TaskStore& store, std::string key, std::string label, double interval,
                   const CheckpointStore::ResumeHook& on_resume)
      : store_(store),
        key_(std::move(key)),
        label_(std::move(label)),
        interval_(interval),
        on_resume_(on_resume),
        last_(Clock::now()) {}

  bool load(TrainingSnapshot& out) override {
    if (!store_.has(key_)) return false;
    try {
      out = record_snapshot(store_.load(key_));
      std::fprintf(stderr, "sirl run: %s continues from its checkpoint at epoch %d\n",
                   label_.c_str(), out.epoch);
      if (on_resume_) {
        const auto f = out.numbers.find("train_flops");
        on_resume_(label_, f != out.numbers.end() ? f->second : 0.0);
      }
      return true;
    } catch (const std::exception& e) {  // corrupt (and then removed by load) or not a snapshot
      std::fprintf(stderr,
                   "sirl run: the training checkpoint of %s is unusable (%s); training it "
                   "from the start\n",
                   key_.c_str(), e.what());
      store_.remove(key_);
      return false;
    }
  }
  // A stop request (jobs/stop_request.h) makes a save due at once; the training then ends here.
  bool due() override {
    return stop_requested() ||
           std::chrono::duration<double>(Clock::now() - last_).count() >= interval_;
  }
  void save(const TrainingSnapshot& s) override {
    store_.commit(snapshot_record(key_, s));
    last_ = Clock::now();
    if (stop_requested()) {
      std::fprintf(stderr, "sirl run: %s saved at epoch %d; stopping (%s)\n", label_.c_str(),
                   s.epoch, stop_signal_name());
      throw StopRequested(label_ + " stopped at epoch " + std::to_string(s.epoch));
    }
  }

 private:
  TaskStore& store_;
  std::string key_;
  std::string label_;  // the task's key, for messages
  double interval_;
  CheckpointStore::ResumeHook on_resume_;
  Clock::time_point last_;
};

std::string hex_words(const std::vector<uint64_t>& w) {
  std::string s;
  char buf[24];
  for (size_t i = 0; i < w.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%s%016llx", i ? "," : "",
                  static_cast<unsigned long long>(w[i]));
    s += buf;
  }
  return s;
}

std::vector<uint64_t> parse_words(const std::string& s) {
  std::vector<uint64_t> w;
  for (size_t at = 0; at < s.size();) {
    const size_t end = std::min(s.find(',', at), s.size());
    const std::string word = s.substr(at, end - at);
    if (word.size() != 16 || word.find_first_not_of("0123456789abcdef") != std::string::npos)
      throw std::runtime_error("a random-stream state is not 16 hex digits");
    w.push_back(std::stoull(word, nullptr, 16));
    at = end + 1;
  }
  return w;
}

}  // namespace

TaskRecord snapshot_record(const std::string& key, const TrainingSnapshot& s) {
  TaskRecord r;
  r.key = key;
  r.kind = "checkpoint";
  r.num["epoch"] = s.epoch;
  for (const auto& [name, v] : s.floats) r.arrays["f/" + name] = {{uint64_t(v.size())}, v};
  for (const auto& [name, x] : s.numbers) r.num["n/" + name] = x;
  for (const auto& [name, w] : s.words) r.text["w/" + name] = hex_words(w);
  return r;
}

TrainingSnapshot record_snapshot(const TaskRecord& r) {
  if (r.kind != "checkpoint" || !r.num.count("epoch"))
    throw std::runtime_error("not a training checkpoint");
  TrainingSnapshot s;
  s.epoch = int(r.num.at("epoch"));
  for (const auto& [name, a] : r.arrays)
    if (name.starts_with("f/")) s.floats[name.substr(2)] = a.data;
  for (const auto& [name, x] : r.num)
    if (name.starts_with("n/")) s.numbers[name.substr(2)] = x;
  for (const auto& [name, t] : r.text)
    if (name.starts_with("w/")) s.words[name.substr(2)] = parse_words(t);
  return s;
}

namespace {
// The checkpoint folder is the cache's own: a symbolic link there would make the store read and
// delete files in whatever folder it points to.
std::filesystem::path own_folder(std::filesystem::path dir) {
  if (std::filesystem::is_symlink(dir))
    throw std::runtime_error(dir.string() +
                             " is a symbolic link: the task cache never follows links inside "
                             "itself (its files would be deleted elsewhere); remove the link");
  return dir;
}
}  // namespace

CheckpointStore::CheckpointStore(std::filesystem::path dir, double interval_seconds)
    : store_(own_folder(std::move(dir))), interval_(interval_seconds) {}

std::unique_ptr<Checkpointer> CheckpointStore::for_task(const std::string& id,
                                                        const std::string& label) {
  if (interval_ < 0) return nullptr;
  return std::make_unique<FileCheckpointer>(store_, id, label, interval_, on_resume_);
}

}  // namespace sirl
