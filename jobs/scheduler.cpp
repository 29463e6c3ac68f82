#include "jobs/scheduler.h"

#include "jobs/ready_queue.h"

#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <exception>
#include <mutex>

namespace sirl {

std::vector<double> upward_rank(const Plan& plan) {
  const int n = int(plan.tasks.size());
  std::vector<double> rank(n, 0);
  // Dependencies always precede their dependents in the plan, so one reverse sweep suffices.
  std::vector<double> best_child(n, 0);
  for (int i = n - 1; i >= 0; --i) {
    rank[i] = plan.tasks[i].flops + best_child[i];
    for (int d : plan.tasks[i].deps) best_child[d] = std::max(best_child[d], rank[i]);
  }
  return rank;
}

void run_dag(const Plan& plan, const std::vector<char>& pending, int threads,
             const std::function<void(int)>& work) {
  ReadyQueue queue(plan, pending);
  std::mutex mu;
  std::exception_ptr error;
  bool stop = false;
  tbb::task_arena arena(std::max(1, threads));
  tbb::task_group group;
  // Each spawned runner takes the best ready task at the moment it starts.
  std::function<void()> runner = [&]() {
    int i;
    {
      std::lock_guard lock(mu);
      if (stop || queue.empty()) return;
      i = queue.pop();
    }
    try {
      work(i);
    } catch (...) {
      std::lock_guard lock(mu);
      if (!error) error = std::current_exception();
      stop = true;
      return;
    }
    int spawn = 0;
    {
      std::lock_guard lock(mu);
      spawn = queue.finish(i);
    }
    for (int k = 0; k < spawn; ++k) group.run(runner);
  };
  arena.execute([&] {
    const size_t initial = queue.size();
    for (size_t k = 0; k < initial; ++k) group.run(runner);
    group.wait();
  });
  if (error) std::rethrow_exception(error);
}

}  // namespace sirl
