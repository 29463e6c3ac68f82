#include "jobs/schedule_sim.h"

#include <algorithm>
#include <deque>
#include <limits>
#include <stdexcept>

#include "jobs/ready_queue.h"
#include "jobs/scheduler.h"

namespace sirl {

namespace {

struct Running {
  int task, worker, node, cores;
  double remaining;  // seconds of work left at full speed
  double demand;     // bytes/s of main memory it asks for at full speed
  double started;
};

// The longest chain of task times (each task alone on one core) through the pending tasks.
void critical_path(const Plan& plan, const std::vector<double>& seconds,
                   const std::vector<char>& pending, ScheduleResult& r) {
  const size_t n = plan.tasks.size();
  std::vector<double> finish(n, 0);
  std::vector<int> from(n, -1);
  int last = -1;
  for (size_t i = 0; i < n; ++i) {  // dependencies precede their dependents in a plan
    if (!pending[i]) continue;
    double start = 0;
    for (int d : plan.tasks[i].deps)
      if (pending[size_t(d)] && finish[size_t(d)] > start) {
        start = finish[size_t(d)];
        from[i] = d;
      }
    finish[i] = start + seconds[i];
    if (last < 0 || finish[i] > finish[size_t(last)]) last = int(i);
  }
  for (int i = last; i >= 0; i = from[size_t(i)])
    r.critical_path.insert(r.critical_path.begin(), i);
  r.critical_path_seconds = last >= 0 ? finish[size_t(last)] : 0;
}

// One simulation: the model's workers (MPI ranks or the thread pool's cores), the ready queue,
// the tasks running with the work they have left, and rank 0's commits, advanced from event to
// event (a task ends or a commit ends).
class Simulation {
 public:
  Simulation(const Plan& plan, const std::vector<double>& seconds, const std::vector<char>& pending,
             const ClusterModel& m, ScheduleResult& r)
      : plan_(plan), seconds_(seconds), m_(m), r_(r), queue_(plan, pending) {
    width_ = m.mpi ? m.threads_per_worker : 1;
    if (width_ < 1 || width_ > m.cores_per_node)
      throw std::invalid_argument("a worker's threads must fit on one node");
    if (m.mpi) {  // worker w lives on node_of_[w] and holds width_ cores
      for (int node = 0; node < m.nodes; ++node) {
        const int cores = m.cores_per_node - (node == 0 ? 1 : 0);  // rank 0 dispatches on node 0
        for (int w = 0; w < cores / width_; ++w) node_of_.push_back(node);
      }
      if (node_of_.empty())
        throw std::invalid_argument(
            "no core is left for a worker rank beside rank 0 (the dispatcher)");
    }
    task_cores_ = m.mpi ? int(node_of_.size()) * width_ : m.cores_per_node;
    r.workers = m.mpi ? int(node_of_.size()) : m.cores_per_node;
    for (int w = 0; w < int(node_of_.size()); ++w) idle_.push_back(w);
    node_workers_.assign(size_t(m.nodes), 0);
    for (int node : node_of_) ++node_workers_[size_t(node)];
    gang_.resize(node_of_.size());
    free_cores_ = m.cores_per_node;
  }

  void run() {
    dispatch();
    while (!running_.empty() || committing_.first >= 0) {
      const size_t next = advance_to_next_event();
      if (next == running_.size())
        end_commit();
      else
        end_task(next);
      dispatch();
    }
    r_.makespan = now_;
    r_.utilisation = now_ > 0 ? r_.core_seconds / (now_ * task_cores_) : 0;
  }

 private:
  void start(int i, int worker, int node, int cores) {
    const double alone = seconds_[size_t(i)] / task_speedup(cores, m_.serial_fraction);
    const Task& t = plan_.tasks[size_t(i)];
    running_.push_back({i, worker, node, cores,
                        alone + (m_.mpi ? m_.mpi_task_seconds : m_.commit_seconds),
                        alone > 0 ? t.stream_bytes / alone : 0.0, now_});
  }

  void dispatch() { m_.mpi ? dispatch_to_ranks() : dispatch_to_threads(); }

  // As mpi_dispatch: the worker that asked first takes the task, and borrows idle workers of its
  // node when task_threads (counting in workers) says the task is worth their cores.
  void dispatch_to_ranks() {
    while (!idle_.empty() && !queue_.empty()) {
      const int w = idle_.front();
      idle_.pop_front();
      const int i = queue_.pop(), node = node_of_[size_t(w)];
      std::vector<int> same;
      for (int x : idle_)
        if (node_of_[size_t(x)] == node) same.push_back(x);
      const int k = !m_.widen
                        ? 1
                        : task_threads(plan_.tasks[size_t(i)],
                                       {1 + int(same.size()), r_.workers,
                                        node_workers_[size_t(node)], queue_.size(), queue_.rank(i),
                                        queue_.remaining_flops(), queue_.longest_chain()});
      same.resize(size_t(k - 1));
      for (int x : same) idle_.erase(std::find(idle_.begin(), idle_.end(), x));
      gang_[size_t(w)] = same;
      start(i, w, node, k * width_);
    }
  }

  void dispatch_to_threads() {
    while (free_cores_ > 0 && !queue_.empty()) {
      const int i = queue_.pop();
      const int k =
          !m_.widen
              ? 1
              : task_threads(plan_.tasks[size_t(i)],
                             {free_cores_, m_.cores_per_node, m_.max_task_threads, queue_.size(),
                              queue_.rank(i), queue_.remaining_flops(), queue_.longest_chain()});
      free_cores_ -= k;
      start(i, -1, 0, k);
    }
  }

  // Moves time to the next end of a task or of rank 0's commit; returns the task's index in
  // running_, or running_.size() for the commit. Each node's streaming tasks share its bandwidth
  // in proportion to what they ask for.
  size_t advance_to_next_event() {
    node_demand_.assign(size_t(m_.nodes), 0.0);
    for (const Running& x : running_) node_demand_[size_t(x.node)] += x.demand;
    rate_.assign(running_.size(), 1.0);
    double dt = commit_done_ - now_;
    size_t next = running_.size();
    for (size_t k = 0; k < running_.size(); ++k) {
      const double D = node_demand_[size_t(running_[k].node)];
      if (running_[k].demand > 0 && m_.node_bandwidth > 0 && D > m_.node_bandwidth)
        rate_[k] = m_.node_bandwidth / D;
      const double left = running_[k].remaining / rate_[k];
      if (left < dt) {
        dt = left;
        next = k;
      }
    }
    dt = std::max(0.0, dt);
    now_ += dt;
    for (size_t k = 0; k < running_.size(); ++k) {
      running_[k].remaining -= dt * rate_[k];
      r_.bandwidth_stall += dt * (1.0 - rate_[k]);
    }
    return next;
  }

  // Rank 0 finished a commit: the task's dependents become ready.
  void end_commit() {
    queue_.finish(committing_.first);
    committing_ = {-1, -1};
    commit_done_ = std::numeric_limits<double>::infinity();
    begin_commit();
  }

  void end_task(size_t k) {
    const Running x = running_[k];
    running_.erase(running_.begin() + std::ptrdiff_t(k));
    r_.core_seconds += double(x.cores) * (now_ - x.started);
    if (m_.mpi) {  // as mpi_dispatch: the worker (and its gang) take new work at once
      to_commit_.emplace_back(x.task, x.worker);
      idle_.push_back(x.worker);
      for (int w : gang_[size_t(x.worker)]) idle_.push_back(w);
      gang_[size_t(x.worker)].clear();
      begin_commit();
    } else {
      free_cores_ += x.cores;
      queue_.finish(x.task);
    }
  }

  void begin_commit() {
    if (committing_.first >= 0 || to_commit_.empty()) return;
    committing_ = to_commit_.front();
    to_commit_.pop_front();
    commit_done_ = now_ + m_.commit_seconds;
  }

  const Plan& plan_;
  const std::vector<double>& seconds_;
  const ClusterModel& m_;
  ScheduleResult& r_;
  ReadyQueue queue_;
  int width_ = 1, task_cores_ = 0;
  std::vector<int> node_of_;
  std::deque<int> idle_;  // MPI: workers waiting for a task, in the order they reported
  std::vector<int> node_workers_;
  std::vector<std::vector<int>> gang_;  // MPI: the idle workers a task borrowed
  int free_cores_ = 0;                  // threads mode
  std::vector<Running> running_;
  std::deque<std::pair<int, int>> to_commit_;  // MPI: (task, worker) waiting for rank 0
  double commit_done_ = std::numeric_limits<double>::infinity();
  std::pair<int, int> committing_{-1, -1};
  double now_ = 0;
  std::vector<double> node_demand_, rate_;
};

}  // namespace

ScheduleResult simulate_schedule(const Plan& plan, const std::vector<double>& seconds,
                                 const std::vector<char>& pending, const ClusterModel& m) {
  if (seconds.size() != plan.tasks.size() || pending.size() != plan.tasks.size())
    throw std::invalid_argument("simulate_schedule: one time and one pending flag per task");
  if (m.nodes < 1 || m.cores_per_node < 1)
    throw std::invalid_argument("the cluster needs at least one node with one core");
  if (!m.mpi && m.nodes > 1) throw std::invalid_argument("more than one node needs MPI (--mpi)");
  ScheduleResult r;
  critical_path(plan, seconds, pending, r);
  Simulation(plan, seconds, pending, m, r).run();
  return r;
}

}  // namespace sirl
