// jobs/ready_queue: which pending tasks are ready, costliest chain first (upward rank), and which
// become ready when one finishes. Hand-built plans with hand-computed ranks.
#include <gtest/gtest.h>

#include "jobs/ready_queue.h"
#include "jobs/scheduler.h"

namespace sirl {
namespace {

// Tasks with the given FLOPs and dependencies (indices; dependencies precede dependents).
Plan plan_of(const std::vector<std::pair<double, std::vector<int>>>& spec) {
  Plan p;
  for (size_t i = 0; i < spec.size(); ++i) {
    Task t;
    t.key = "t" + std::to_string(i);
    t.flops = spec[i].first;
    t.deps = spec[i].second;
    p.index[t.key] = int(i);
    p.tasks.push_back(t);
  }
  return p;
}

TEST(ReadyQueue, UpwardRankIsTheCostliestChainBelowATask) {
  //  t0 (1) ─► t1 (10) ─► t3 (2)
  //  t2 (5) ─────────────► t3
  const Plan p = plan_of({{1, {}}, {10, {0}}, {5, {}}, {2, {1, 2}}});
  // t3: 2; t1: 10 + 2; t2: 5 + 2; t0: 1 + 12.
  EXPECT_EQ(upward_rank(p), (std::vector<double>{13, 12, 7, 2}));
}

TEST(ReadyQueue, PopsByRankAndReleasesDependentsWhenTheirLastDependencyFinishes) {
  const Plan p = plan_of({{1, {}}, {10, {0}}, {5, {}}, {2, {1, 2}}});
  ReadyQueue q(p, {1, 1, 1, 1});
  EXPECT_EQ(q.remaining(), 4);
  ASSERT_EQ(q.size(), 2u);    // t0 and t2 have no dependencies
  EXPECT_EQ(q.pop(), 0);      // rank 13 before 7
  EXPECT_EQ(q.finish(0), 1);  // t1 ready
  EXPECT_EQ(q.pop(), 1);      // rank 12 before t2's 7
  EXPECT_EQ(q.finish(1), 0);  // t3 still waits for t2
  EXPECT_EQ(q.pop(), 2);
  EXPECT_TRUE(q.empty());
  EXPECT_EQ(q.finish(2), 1);
  EXPECT_EQ(q.pop(), 3);
  EXPECT_EQ(q.finish(3), 0);
  EXPECT_EQ(q.remaining(), 0);
}

TEST(ReadyQueue, TracksTheFlopsOfTheUnfinishedTasksAndExposesRanks) {
  const Plan p = plan_of({{1, {}}, {10, {0}}, {5, {}}, {2, {1, 2}}});
  ReadyQueue q(p, {0, 1, 1, 1});  // t0 is done already
  EXPECT_DOUBLE_EQ(q.remaining_flops(), 17);
  EXPECT_DOUBLE_EQ(q.rank(1), 12);
  EXPECT_DOUBLE_EQ(q.longest_chain(), 12);  // t1 → t3, ready
  EXPECT_EQ(q.pop(), 1);
  EXPECT_DOUBLE_EQ(q.remaining_flops(), 17);  // started is not finished
  EXPECT_DOUBLE_EQ(q.longest_chain(), 12);    // running
  q.finish(1);
  EXPECT_DOUBLE_EQ(q.remaining_flops(), 7);
  EXPECT_DOUBLE_EQ(q.longest_chain(), 7);  // t2 → t3; t3 waits for t2
  EXPECT_EQ(q.pop(), 2);
  q.finish(2);
  EXPECT_DOUBLE_EQ(q.longest_chain(), 2);  // t3, ready
}

TEST(ReadyQueue, ADependencyThatIsNotPendingCountsAsDone) {
  const Plan p = plan_of({{1, {}}, {10, {0}}, {5, {}}, {2, {1, 2}}});
  // A resumed run: t0 and t2 were committed earlier.
  ReadyQueue q(p, {0, 1, 0, 1});
  EXPECT_EQ(q.remaining(), 2);
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q.pop(), 1);
  EXPECT_EQ(q.finish(1), 1);
  EXPECT_EQ(q.pop(), 3);
}

TEST(ReadyQueue, EqualRanksPopInPlanOrder) {
  const Plan p = plan_of({{3, {}}, {3, {}}, {3, {}}});
  ReadyQueue q(p, {1, 1, 1});
  EXPECT_EQ(q.pop(), 0);
  EXPECT_EQ(q.pop(), 1);
  EXPECT_EQ(q.pop(), 2);
}

}  // namespace
}  // namespace sirl
