// The scheduler: dependency order and stopping at the first error.
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiment/plan.h"
#include "experiment/profile.h"
#include "jobs/scheduler.h"
#include "tests/small_profile.h"

namespace sirl {
namespace {

TEST(Scheduler, RunsEveryPendingTaskAfterItsDependencies) {
  const Plan plan = make_plan(parse_profile(test::kSmallProfile, "t.toml"));
  const int n = int(plan.tasks.size());
  std::vector<char> pending(n, 1);
  pending[0] = 0;  // already done: its dependents must still run
  std::mutex mu;
  std::vector<int> order_of(n, -1);
  int next = 0;
  run_dag(plan, pending, 2, [&](int i) {
    std::lock_guard lock(mu);
    for (int d : plan.tasks[i].deps)
      if (pending[d]) {
        EXPECT_GE(order_of[d], 0) << plan.tasks[i].key << " before its input";
      }
    order_of[i] = next++;
  });
  EXPECT_EQ(next, n - 1);
  EXPECT_EQ(order_of[0], -1);
}

TEST(Scheduler, StopsAtTheFirstErrorAndRethrowsIt) {
  // 40 independent tasks (none waits for another, so only the stop flag can keep them from
  // running) on one thread: the first task to run throws, and no other task may start after it.
  Plan plan;
  for (int i = 0; i < 40; ++i) {
    Task t;
    t.key = "t" + std::to_string(i);
    t.flops = 40 - i;  // t0 has the highest rank: it runs first
    plan.index[t.key] = i;
    plan.tasks.push_back(t);
  }
  std::atomic<int> ran{0};
  const std::vector<char> pending(plan.tasks.size(), 1);
  try {
    run_dag(plan, pending, 1, [&](int i) {
      ++ran;
      throw std::runtime_error("boom in " + plan.tasks[i].key);
    });
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "boom in t0");
  }
  EXPECT_EQ(ran.load(), 1);
}

}  // namespace
}  // namespace sirl
