#include "jobs/mpi_run.h"

// The C API only: Open MPI's deprecated C++ bindings need a library we do not link.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <deque>
#include <exception>
#include <map>
#include <stdexcept>
#include <string>
#include <thread>

#include "experiment/task_kinds.h"
#include "jobs/ready_queue.h"
#include "jobs/scheduler.h"
#include "jobs/stop_request.h"

namespace sirl {

namespace {
// kReady: a worker's first message ("node name\tusable cores"); kTask: {task, threads};
// kHold / kRelease: lend this worker's core to a task of its node, and take it back.
// kStopped: the worker's task ended on a stop request (jobs/stop_request.h), its training saved.
enum Tag {
  kReady = 1,
  kTask = 2,
  kResult = 3,
  kError = 4,
  kStop = 5,
  kHold = 6,
  kRelease = 7,
  kStopped = 8
};
bool g_released = false;

// Waits for the next message from `source` (MPI_ANY_SOURCE: any rank), sleeping between polls
// (20 µs, doubling up to 1 ms) instead of spinning in MPI_Probe: an idle or lending worker leaves
// its core to the threads of a task that borrowed it, and rank 0 leaves its core to the workers
// when ranks share cores (`mpirun --oversubscribe`, or rank 0 beside a full node of workers).
MPI_Status wait_for_message(int source) {
  auto pause = std::chrono::microseconds(20);
  while (true) {
    int flag = 0;
    MPI_Status st;
    MPI_Iprobe(source, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
    if (flag) return st;
    std::this_thread::sleep_for(pause);
    pause = std::min(pause * 2, std::chrono::microseconds(1000));
  }
}

void recv_empty(int tag) {
  MPI_Recv(nullptr, 0, MPI_BYTE, 0, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
}

void send_bytes(const std::string& s, int dest, int tag) {
  MPI_Send(s.data(), int(s.size()), MPI_BYTE, dest, tag, MPI_COMM_WORLD);
}
std::string recv_bytes(const MPI_Status& st) {
  int n = 0;
  MPI_Get_count(&st, MPI_BYTE, &n);
  std::string s(size_t(n), '\0');
  MPI_Recv(s.data(), n, MPI_BYTE, st.MPI_SOURCE, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return s;
}
}  // namespace

bool launched_under_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS"})
    if (const char* s = std::getenv(v); s && std::atoi(s) > 1) return true;
  return false;
}

int mpi_rank_from_env() {
  if (!launched_under_mpi()) return 0;
  for (const char* v : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"})
    if (const char* s = std::getenv(v)) return std::atoi(s);
  return 0;
}

std::pair<int, int> mpi_start() {
  int inited = 0;
  MPI_Initialized(&inited);
  if (!inited) MPI_Init(nullptr, nullptr);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return {rank, size};
}

void mpi_stop() {
  int fin = 0;
  MPI_Finalized(&fin);
  if (!fin) MPI_Finalize();
}

void mpi_release_workers() {
  if (g_released) return;
  g_released = true;
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  for (int w = 1; w < size; ++w) MPI_Send(nullptr, 0, MPI_BYTE, w, kStop, MPI_COMM_WORLD);
}

void mpi_abort(int code) {
  MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

namespace {

// Rank 0's side of a run: what it knows of each worker (its node, its usable cores, its task and
// the workers it borrowed), the ready queue, and the first failure.
class Dispatcher {
 public:
  Dispatcher(const Plan& plan, const std::vector<char>& pending, int threads_per_worker,
             const std::function<void(int, const TaskRecord&)>& on_result)
      : plan_(plan), on_result_(on_result), queue_(plan, pending) {
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
    width_ = std::max(1, threads_per_worker);
    ran_.assign(size_t(size_), 0);
    running_.assign(size_t(size_), -1);
    node_.assign(size_t(size_), -1);
    usable_.assign(size_t(size_), 1);
    gang_.resize(size_t(size_));
  }

  std::vector<int> run() {
    while (true) {
      hand_out();
      if (busy_ == 0 && (queue_.remaining() == 0 || halted())) break;
      const MPI_Status st = wait_for_message(MPI_ANY_SOURCE);
      const std::string msg = recv_bytes(st);
      if (st.MPI_TAG == kReady)
        on_ready(st.MPI_SOURCE, msg);
      else if (st.MPI_TAG == kResult || st.MPI_TAG == kError || st.MPI_TAG == kStopped)
        on_done(st.MPI_SOURCE, st.MPI_TAG, msg);
    }
    // Every worker's first message is received, even when there was nothing to run.
    while (reported_ < size_ - 1) {
      recv_bytes(wait_for_message(MPI_ANY_SOURCE));
      ++reported_;
    }
    mpi_release_workers();
    if (failure_) std::rethrow_exception(failure_);
    if (!error_.empty()) throw std::runtime_error(error_);
    if (queue_.remaining() > 0 && (stopped_ || stop_requested()))
      throw StopRequested("the run stopped with tasks left");
    return ran_;
  }

 private:
  // Hands the ready tasks to idle workers. The first task waits for every worker's report: a
  // task borrows only workers it knows of.
  // No task starts after a failure or a stop request (this rank's, or a worker's).
  bool halted() const { return !error_.empty() || stopped_ || stop_requested(); }

  void hand_out() {
    while (!halted() && reported_ == size_ - 1 && !idle_.empty() && !queue_.empty()) {
      const int w = idle_.front();
      idle_.pop_front();
      const int i = queue_.pop();
      // As the thread scheduler, counting in workers: a big task alone or on a critical chain
      // takes idle workers of its node too, as far as its process may run threads on their
      // cores (a rank bound to its own core lends nothing). The simulator does the same.
      std::vector<int> same;
      for (int x : idle_)
        if (node_[x] == node_[w]) same.push_back(x);
      const int k = task_threads(
          plan_.tasks[size_t(i)],
          {1 + int(same.size()), size_ - 1,
           std::min(node_workers_[size_t(node_[w])], std::max(1, usable_[w] / width_)),
           queue_.size(), queue_.rank(i), queue_.remaining_flops(), queue_.longest_chain()});
      same.resize(size_t(k - 1));
      for (int x : same) {
        idle_.erase(std::find(idle_.begin(), idle_.end(), x));
        MPI_Send(nullptr, 0, MPI_BYTE, x, kHold, MPI_COMM_WORLD);
      }
      gang_[w] = same;
      const int msg[2] = {i, k * width_};
      MPI_Send(msg, 2, MPI_INT, w, kTask, MPI_COMM_WORLD);
      running_[w] = i;
      ++busy_;
    }
  }

  // A worker's first message: "node name\tusable cores".
  void on_ready(int w, const std::string& msg) {
    const size_t tab = msg.find('\t');
    const auto [it, added] = node_ids_.emplace(msg.substr(0, tab), int(node_ids_.size()));
    if (added) node_workers_.push_back(0);
    node_[w] = it->second;
    ++node_workers_[size_t(node_[w])];
    usable_[w] = tab == std::string::npos ? 1 : std::max(1, std::atoi(msg.c_str() + tab + 1));
    idle_.push_back(w);
    ++reported_;
  }

  // Worker w finished its task: a result (a serialized record), an error (its message), or a
  // stop (its training saved; the task stays pending for the rerun).
  void on_done(int w, int tag, const std::string& msg) {
    const int i = running_[w];
    running_[w] = -1;
    --busy_;
    idle_.push_back(w);
    for (int x : gang_[w]) {
      MPI_Send(nullptr, 0, MPI_BYTE, x, kRelease, MPI_COMM_WORLD);
      idle_.push_back(x);
    }
    gang_[w].clear();
    if (tag == kStopped) {
      stopped_ = true;
      return;
    }
    if (tag == kError) {
      if (error_.empty()) error_ = "rank " + std::to_string(w) + ": " + msg;
      return;
    }
    // The worker takes its next task before rank 0 commits this result: it need not wait for
    // the write. Only tasks ready before this result go out; its dependents become ready once it
    // is committed (they read it from the staging folder).
    hand_out();
    // A result rank 0 cannot take (a commit failing for want of space, a malformed record) ends
    // the run like a failed task: no new task starts, and the running ones are received before
    // the workers are released. Leaving now would leave them blocked in MPI_Send of their
    // results, and mpirun waiting on them.
    try {
      const TaskRecord rec = deserialize(msg);
      if (rec.key != plan_.tasks[i].key)
        throw std::runtime_error("rank " + std::to_string(w) + " returned " + rec.key +
                                 " for task " + plan_.tasks[i].key);
      on_result_(i, rec);
      queue_.finish(i);
      ++ran_[w];
    } catch (const std::exception& e) {
      if (error_.empty()) {  // the first failure is the one reported
        failure_ = std::current_exception();
        error_ = e.what();
      }
    }
  }

  const Plan& plan_;
  const std::function<void(int, const TaskRecord&)>& on_result_;
  ReadyQueue queue_;
  int size_ = 1, width_ = 1, busy_ = 0, reported_ = 0;
  std::vector<int> ran_;      // results received per rank
  std::vector<int> running_;  // each worker's task (-1: none)
  std::deque<int> idle_;
  // Each worker's node (by processor name), how many cores its process may use, and the idle
  // workers of its node it borrowed for its current task.
  std::map<std::string, int> node_ids_;
  std::vector<int> node_, usable_, node_workers_;
  std::vector<std::vector<int>> gang_;
  std::string error_;           // the first failure, which stops dispatching
  bool stopped_ = false;        // a worker's task ended on a stop request
  std::exception_ptr failure_;  // rank 0's own, rethrown as it was
};

}  // namespace

std::vector<int> mpi_dispatch(const Plan& plan, const std::vector<char>& pending,
                              int threads_per_worker,
                              const std::function<void(int, const TaskRecord&)>& on_result) {
  return Dispatcher(plan, pending, threads_per_worker, on_result).run();
}

void mpi_work(const Plan& plan, RunContext& ctx) {
  char name[MPI_MAX_PROCESSOR_NAME] = {};
  int len = 0;
  MPI_Get_processor_name(name, &len);
  send_bytes(std::string(name, size_t(len)) + "\t" + std::to_string(usable_cores()), 0, kReady);
  while (true) {
    MPI_Status st = wait_for_message(0);
    if (st.MPI_TAG == kStop) {
      recv_empty(kStop);
      return;
    }
    if (st.MPI_TAG == kHold) {  // lend this core until the borrowing task ends (or the run)
      recv_empty(kHold);
      st = wait_for_message(0);
      recv_empty(st.MPI_TAG);
      if (st.MPI_TAG == kStop) return;
      continue;
    }
    int msg[2] = {-1, 1};
    MPI_Recv(msg, 2, MPI_INT, 0, kTask, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    try {
      Task t = plan.tasks.at(size_t(msg[0]));
      t.threads = std::max(1, msg[1]);
      send_bytes(serialize(run_task(t, ctx)), 0, kResult);
    } catch (const StopRequested& e) {
      send_bytes(e.what(), 0, kStopped);
    } catch (const std::exception& e) {
      send_bytes(e.what(), 0, kError);
    }
  }
}

}  // namespace sirl
