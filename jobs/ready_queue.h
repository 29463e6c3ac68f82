// The dependency bookkeeping shared by the thread scheduler and the MPI dispatcher: which
// pending tasks are ready, in order of upward rank (costliest chains first), and which become
// ready when one finishes. Not thread-safe: callers hold their own lock.
#pragma once
#include <queue>
#include <set>
#include <vector>

#include "experiment/plan.h"

namespace sirl {

// Each task's upward rank: its FLOPs plus the costliest chain of tasks that wait on it (the
// order ready tasks start in; `sirl plan` and tests read it too).
std::vector<double> upward_rank(const Plan& plan);

class ReadyQueue {
 public:
  // pending[i]: task i still has to run; a dependency that is not pending counts as done.
  ReadyQueue(const Plan& plan, const std::vector<char>& pending);
  bool empty() const { return ready_.empty(); }
  size_t size() const { return ready_.size(); }
  int remaining() const { return remaining_; }                 // pending tasks not yet finished
  double remaining_flops() const { return remaining_flops_; }  // their Σ FLOPs
  // The largest upward rank among the ready and the started, unfinished tasks: the longest
  // chain of work still ahead, in FLOPs.
  double longest_chain() const { return active_.empty() ? 0.0 : *active_.rbegin(); }
  double rank(int i) const { return rank_[size_t(i)]; }  // upward rank (FLOPs)
  int top() const { return ready_.top(); }               // the next pop(), not removed
  int pop();                                             // the ready task of highest rank
  // Task i finished: returns how many tasks became ready.
  int finish(int i);

 private:
  std::vector<double> rank_;
  std::vector<int> waiting_;
  std::vector<std::vector<int>> dependents_;
  struct ByRank {
    const std::vector<double>* rank;
    bool operator()(int a, int b) const {
      return (*rank)[a] < (*rank)[b] || ((*rank)[a] == (*rank)[b] && a > b);
    }
  };
  std::priority_queue<int, std::vector<int>, ByRank> ready_;
  int remaining_ = 0;
  double remaining_flops_ = 0;
  std::multiset<double> active_;  // ranks of the ready and running tasks
  const Plan* plan_;
};

}  // namespace sirl
