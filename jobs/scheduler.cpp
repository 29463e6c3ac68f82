#include "jobs/scheduler.h"

#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <queue>

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
  const int n = int(plan.tasks.size());
  const std::vector<double> rank = upward_rank(plan);
  std::vector<int> waiting(n, 0);
  std::vector<std::vector<int>> dependents(n);
  for (int i = 0; i < n; ++i) {
    if (!pending[i]) continue;
    for (int d : plan.tasks[i].deps)
      if (pending[d]) {
        ++waiting[i];
        dependents[d].push_back(i);
      }
  }
  auto cmp = [&](int a, int b) { return rank[a] < rank[b] || (rank[a] == rank[b] && a > b); };
  std::priority_queue<int, std::vector<int>, decltype(cmp)> ready(cmp);
  for (int i = 0; i < n; ++i)
    if (pending[i] && waiting[i] == 0) ready.push(i);

  std::mutex mu;
  std::exception_ptr error;
  std::atomic<bool> stop{false};
  tbb::task_arena arena(std::max(1, threads));
  tbb::task_group group;
  // Each spawned runner takes the best ready task at the moment it starts.
  std::function<void()> runner = [&]() {
    int i;
    {
      std::lock_guard lock(mu);
      if (stop || ready.empty()) return;
      i = ready.top();
      ready.pop();
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
      for (int j : dependents[i])
        if (--waiting[j] == 0) {
          ready.push(j);
          ++spawn;
        }
    }
    for (int k = 0; k < spawn; ++k) group.run(runner);
  };
  arena.execute([&] {
    const size_t initial = ready.size();
    for (size_t k = 0; k < initial; ++k) group.run(runner);
    group.wait();
  });
  if (error) std::rethrow_exception(error);
}

}  // namespace sirl
