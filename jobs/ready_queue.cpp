#include "jobs/ready_queue.h"

#include <algorithm>

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

ReadyQueue::ReadyQueue(const Plan& plan, const std::vector<char>& pending)
    : rank_(upward_rank(plan)),
      waiting_(plan.tasks.size(), 0),
      dependents_(plan.tasks.size()),
      ready_(ByRank{&rank_}),
      plan_(&plan) {
  const int n = int(plan.tasks.size());
  for (int i = 0; i < n; ++i) {
    if (!pending[i]) continue;
    ++remaining_;
    remaining_flops_ += plan.tasks[size_t(i)].flops;
    for (int d : plan.tasks[i].deps)
      if (pending[d]) {
        ++waiting_[i];
        dependents_[d].push_back(i);
      }
  }
  for (int i = 0; i < n; ++i)
    if (pending[i] && waiting_[i] == 0) {
      ready_.push(i);
      active_.insert(rank_[size_t(i)]);
    }
}

int ReadyQueue::pop() {
  const int i = ready_.top();
  ready_.pop();
  return i;
}

int ReadyQueue::finish(int i) {
  --remaining_;
  remaining_flops_ -= plan_->tasks[size_t(i)].flops;
  active_.erase(active_.find(rank_[size_t(i)]));
  int n = 0;
  for (int j : dependents_[i])
    if (--waiting_[j] == 0) {
      ready_.push(j);
      active_.insert(rank_[size_t(j)]);
      ++n;
    }
  return n;
}

}  // namespace sirl
