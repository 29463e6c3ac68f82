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

  // Task slots: worker w lives on node_of[w] and holds `width` cores.
  std::vector<int> node_of;
  const int width = m.mpi ? m.threads_per_worker : 1;
  if (width < 1 || width > m.cores_per_node)
    throw std::invalid_argument("a worker's threads must fit on one node");
  if (m.mpi) {
    for (int node = 0; node < m.nodes; ++node) {
      const int cores = m.cores_per_node - (node == 0 ? 1 : 0);  // rank 0 dispatches on node 0
      for (int w = 0; w < cores / width; ++w) node_of.push_back(node);
    }
    if (node_of.empty())
      throw std::invalid_argument(
          "no core is left for a worker rank beside rank 0 (the dispatcher)");
  }
  const int task_cores = m.mpi ? int(node_of.size()) * width : m.cores_per_node;
  r.workers = m.mpi ? int(node_of.size()) : m.cores_per_node;

  ReadyQueue queue(plan, pending);
  std::deque<int> idle;  // MPI: workers waiting for a task, in the order they reported
  for (int w = 0; w < int(node_of.size()); ++w) idle.push_back(w);
  std::vector<int> node_workers(size_t(m.nodes), 0);
  for (int node : node_of) ++node_workers[size_t(node)];
  std::vector<std::vector<int>> gang(node_of.size());  // MPI: the idle workers a task borrowed
  int free_cores = m.cores_per_node;                   // threads mode
  std::vector<Running> running;
  std::deque<std::pair<int, int>> to_commit;  // MPI: (task, worker) waiting for rank 0
  double commit_done = std::numeric_limits<double>::infinity();
  std::pair<int, int> committing{-1, -1};
  double now = 0;

  auto start = [&](int i, int worker, int node, int cores) {
    const double alone = seconds[size_t(i)] / task_speedup(cores, m.serial_fraction);
    const Task& t = plan.tasks[size_t(i)];
    running.push_back({i, worker, node, cores,
                       alone + (m.mpi ? m.mpi_task_seconds : m.commit_seconds),
                       alone > 0 ? t.stream_bytes / alone : 0.0, now});
  };
  auto dispatch = [&] {
    if (m.mpi) {
      // As mpi_dispatch: the worker that asked first takes the task, and borrows idle workers of
      // its node when task_threads (counting in workers) says the task is worth their cores.
      while (!idle.empty() && !queue.empty()) {
        const int w = idle.front();
        idle.pop_front();
        const int i = queue.pop(), node = node_of[size_t(w)];
        std::vector<int> same;
        for (int x : idle)
          if (node_of[size_t(x)] == node) same.push_back(x);
        const int k = !m.widen
                          ? 1
                          : task_threads(plan.tasks[size_t(i)],
                                         {1 + int(same.size()), r.workers,
                                          node_workers[size_t(node)], queue.size(), queue.rank(i),
                                          queue.remaining_flops(), queue.longest_chain()});
        same.resize(size_t(k - 1));
        for (int x : same) idle.erase(std::find(idle.begin(), idle.end(), x));
        gang[size_t(w)] = same;
        start(i, w, node, k * width);
      }
    } else {
      while (free_cores > 0 && !queue.empty()) {
        const int i = queue.pop();
        const int k =
            !m.widen
                ? 1
                : task_threads(plan.tasks[size_t(i)],
                               {free_cores, m.cores_per_node, m.max_task_threads, queue.size(),
                                queue.rank(i), queue.remaining_flops(), queue.longest_chain()});
        free_cores -= k;
        start(i, -1, 0, k);
      }
    }
  };
  auto begin_commit = [&] {
    if (committing.first >= 0 || to_commit.empty()) return;
    committing = to_commit.front();
    to_commit.pop_front();
    commit_done = now + m.commit_seconds;
  };

  dispatch();
  std::vector<double> node_demand(size_t(m.nodes)), rate;
  while (!running.empty() || committing.first >= 0) {
    // Each node's streaming tasks share its bandwidth in proportion to what they ask for.
    std::fill(node_demand.begin(), node_demand.end(), 0.0);
    for (const Running& x : running) node_demand[size_t(x.node)] += x.demand;
    rate.assign(running.size(), 1.0);
    double dt = commit_done - now;
    size_t next = running.size();
    for (size_t k = 0; k < running.size(); ++k) {
      const double D = node_demand[size_t(running[k].node)];
      if (running[k].demand > 0 && m.node_bandwidth > 0 && D > m.node_bandwidth)
        rate[k] = m.node_bandwidth / D;
      const double left = running[k].remaining / rate[k];
      if (left < dt) {
        dt = left;
        next = k;
      }
    }
    dt = std::max(0.0, dt);
    now += dt;
    for (size_t k = 0; k < running.size(); ++k) {
      running[k].remaining -= dt * rate[k];
      r.bandwidth_stall += dt * (1.0 - rate[k]);
    }
    if (next == running.size()) {  // rank 0 finished a commit: dependents become ready
      queue.finish(committing.first);
      committing = {-1, -1};
      commit_done = std::numeric_limits<double>::infinity();
      begin_commit();
    } else {
      const Running x = running[next];
      running.erase(running.begin() + std::ptrdiff_t(next));
      r.core_seconds += double(x.cores) * (now - x.started);
      if (m.mpi) {  // as mpi_dispatch: the worker (and its gang) take new work at once
        to_commit.emplace_back(x.task, x.worker);
        idle.push_back(x.worker);
        for (int w : gang[size_t(x.worker)]) idle.push_back(w);
        gang[size_t(x.worker)].clear();
        begin_commit();
      } else {
        free_cores += x.cores;
        queue.finish(x.task);
      }
    }
    dispatch();
  }
  r.makespan = now;
  r.utilisation = now > 0 ? r.core_seconds / (now * task_cores) : 0;
  return r;
}

}  // namespace sirl
