// The run's status line: its share done, rate and ETA, worked out by hand.
#include <gtest/gtest.h>

#include <string>

#include "jobs/progress.h"

namespace sirl {
namespace {

TEST(Progress, TheEtaIsTheFlopsLeftAtTheRateOfTasksRunHere) {
  // 100 GFLOP in all, 50 done in 10 s, all run here: 5 GFLOP/s, 50 left → 10 s.
  EXPECT_EQ(progress_line(3, 10, 50e9, 50e9, 50e9, 100e9, 10),
            "[3/10 tasks]  50.0% | 5.0 GFLOP/s | elapsed 10s | ETA 10s");
  // The same, but 40 of the 50 were a task resumed from a checkpoint: the rate counts the 10
  // GFLOP run whole here (1 GFLOP/s), so the 50 left take 50 s, not 10.
  EXPECT_EQ(progress_line(3, 10, 50e9, 10e9, 10e9, 100e9, 10),
            "[3/10 tasks]  50.0% | 1.0 GFLOP/s | elapsed 10s | ETA 50s");
  // Only a resumed task finished: no rate yet, so no ETA.
  EXPECT_EQ(progress_line(1, 10, 40e9, 0, 0, 100e9, 10),
            "[1/10 tasks]  40.0% | 0.0 GFLOP/s | elapsed 10s | ETA ?");
  // Done: ETA 0 whatever the rate.
  EXPECT_EQ(progress_line(10, 10, 100e9, 0, 0, 100e9, 125),
            "[10/10 tasks] 100.0% | 0.0 GFLOP/s | elapsed 2m05s | ETA 0s");
  // Tasks that stopped early by a rule the plan did not know: 50 of the estimated 100 GFLOP done
  // in 10 s, but they executed 5 GFLOP: the speed shown is the executed FLOPs over the time, while
  // the ETA stays in the estimate's units at the estimate's rate.
  EXPECT_EQ(progress_line(3, 10, 50e9, 50e9, 5e9, 100e9, 10),
            "[3/10 tasks]  50.0% | 0.5 GFLOP/s | elapsed 10s | ETA 10s");
  // No FLOP estimates (every task 0): the ETA by task count, 2 of 8 in 30 s → 90 s more.
  EXPECT_EQ(progress_line(2, 8, 0, 0, 0, 0, 30),
            "[2/8 tasks]  25.0% | 0.0 GFLOP/s | elapsed 30s | ETA 1m30s");
}

// The bookkeeping behind the line: a task named resumed counts toward the share done, not the
// rate; every other task toward both.
TEST(Progress, ResumedTasksCountTowardTheShareDoneButNotTheRate) {
  Progress p(3, 100e9, /*quiet=*/true);
  p.set_resumed({"cell/resumed"});
  p.task_done("cell/resumed", 60e9, 1.0);
  Progress::Counts c = p.counts();
  EXPECT_EQ(c.done, 1);
  EXPECT_DOUBLE_EQ(c.done_flops, 60e9);
  EXPECT_DOUBLE_EQ(c.rate_flops, 0);
  p.task_done("cell/fresh", 30e9, 1.0);
  p.task_done("rep/fresh", 10e9, 1.0);
  c = p.counts();
  EXPECT_EQ(c.done, 3);
  EXPECT_DOUBLE_EQ(c.done_flops, 100e9);
  EXPECT_DOUBLE_EQ(c.rate_flops, 40e9);
}

// A resumed task whose checkpoint counted the FLOPs it had executed: what it ran here counts
// toward the rate, so a restarted run whose first finished tasks were all resumed has an ETA.
TEST(Progress, AResumedTaskCountsTheWorkItRanHereTowardTheRate) {
  Progress p(2, 100e9, /*quiet=*/true);
  p.set_resumed({"rep/counted", "cell/uncounted"});
  p.resumed_from("rep/counted", 45e9);  // 45 of its 60 GFLOP done before this process
  p.resumed_from("cell/uncounted", 0);  // its checkpoint does not count them
  p.task_done("rep/counted", 60e9, 1.0);
  EXPECT_DOUBLE_EQ(p.counts().rate_flops, 15e9);
  EXPECT_DOUBLE_EQ(p.counts().done_flops, 60e9);
  p.task_done("cell/uncounted", 40e9, 1.0);
  EXPECT_DOUBLE_EQ(p.counts().rate_flops, 15e9);  // still out of the rate, as before
  // A checkpoint that counted more than the plan's estimate adds nothing, never a negative.
  Progress q(1, 10e9, true);
  q.set_resumed({"rep/over"});
  q.resumed_from("rep/over", 12e9);
  q.task_done("rep/over", 10e9, 1.0);
  EXPECT_DOUBLE_EQ(q.counts().rate_flops, 0);
}

// A task's executed FLOPs feed the speed shown, its estimate the ETA; a resumed one counts the part
// it ran here in both (that share of its estimate); a task another process computed, in neither.
TEST(Progress, ExecutedFlopsAreTheSpeedAndEstimatesTheEta) {
  Progress p(4, 200e9, /*quiet=*/true);
  p.task_done("rep/stopped", 100e9, 1.0, 10e9);  // estimated 100, stopped after 10
  p.task_done("cell/fresh", 20e9, 1.0);          // executed not given: the estimate
  Progress::Counts c = p.counts();
  EXPECT_DOUBLE_EQ(c.done_flops, 120e9);
  EXPECT_DOUBLE_EQ(c.rate_flops, 120e9);
  EXPECT_DOUBLE_EQ(c.executed_flops, 30e9);
  p.set_resumed({"rep/resumed"});
  p.resumed_from("rep/resumed", 30e9);          // 30 of its 40 executed before this process
  p.task_done("rep/resumed", 60e9, 1.0, 40e9);  // a quarter of it ran here: 15 of the estimate
  p.done_elsewhere("cell/elsewhere", 20e9);
  c = p.counts();
  EXPECT_EQ(c.done, 4);
  EXPECT_DOUBLE_EQ(c.done_flops, 200e9);
  EXPECT_DOUBLE_EQ(c.rate_flops, 135e9);
  EXPECT_DOUBLE_EQ(c.executed_flops, 40e9);
}

}  // namespace
}  // namespace sirl
