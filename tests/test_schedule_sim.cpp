// The schedule simulator (`sirl plan`) on hand-made DAGs whose makespans are worked out by hand,
// and the cores-per-task rule shared with the thread scheduler.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "jobs/schedule_sim.h"
#include "jobs/scheduler.h"

namespace sirl {
namespace {

// Tasks with the given seconds (flops = seconds × 1e10, so upward rank follows time) and
// dependencies; every plan lists inputs before their users, as make_plan does.
Plan plan_of(const std::vector<double>& seconds, const std::vector<std::vector<int>>& deps) {
  Plan p;
  for (size_t i = 0; i < seconds.size(); ++i) {
    Task t;
    t.key = "t" + std::to_string(i);
    t.flops = seconds[i] * 1e10;
    t.bytes = 2 * kThreadedTaskBytes;  // big steps: worth threads when alone
    t.deps = deps[i];
    p.index[t.key] = int(i);
    p.tasks.push_back(t);
  }
  return p;
}

ClusterModel cores(int n, int max_task_threads = 1) {
  ClusterModel m;
  m.cores_per_node = n;
  m.max_task_threads = max_task_threads;
  m.commit_seconds = 0;
  m.mpi_task_seconds = 0;
  m.serial_fraction = 0.25;  // the cases below are worked by hand at this fraction
  return m;
}

ScheduleResult sim(const Plan& p, const std::vector<double>& s, const ClusterModel& m) {
  return simulate_schedule(p, s, std::vector<char>(s.size(), 1), m);
}

TEST(ScheduleSim, AChainTakesTheSumOfItsTasksWhateverTheCores) {
  const std::vector<double> s{1, 2, 3};
  const Plan p = plan_of(s, {{}, {0}, {1}});
  ClusterModel m = cores(4);
  m.commit_seconds = 0.5;  // in the worker: each task holds its core 0.5 s longer
  const ScheduleResult r = sim(p, s, m);
  EXPECT_DOUBLE_EQ(r.makespan, 6 + 3 * 0.5);
  EXPECT_EQ(r.critical_path, (std::vector<int>{0, 1, 2}));
  EXPECT_DOUBLE_EQ(r.critical_path_seconds, 6);
}

TEST(ScheduleSim, IndependentTasksFillTheCores) {
  const std::vector<double> s{1, 1, 1, 1};
  const Plan p = plan_of(s, {{}, {}, {}, {}});
  const ScheduleResult r = sim(p, s, cores(2));
  EXPECT_DOUBLE_EQ(r.makespan, 2);
  EXPECT_DOUBLE_EQ(r.utilisation, 1);
  EXPECT_EQ(r.critical_path.size(), 1u);
}

TEST(ScheduleSim, TheLongestChainStartsFirstAsTheReadyQueueRanksIt) {
  // 2 cores; A(2), B(2), C(1) → D(3). Ranks: C 4, D 3, A 2, B 2. C and A start; at t = 1 C is
  // done and D (rank 3) takes its core before B, ending at 4; B runs 2–4. Makespan 4. A
  // first-come order (A, B, then C, D) would end at 6.
  const std::vector<double> s{2, 2, 1, 3};
  const Plan p = plan_of(s, {{}, {}, {}, {2}});
  EXPECT_DOUBLE_EQ(sim(p, s, cores(2)).makespan, 4);
}

TEST(ScheduleSim, ALoneBigTaskTakesTheIdleCores) {
  const std::vector<double> s{8};
  const Plan p = plan_of(s, {{}});
  ClusterModel m = cores(4, 4);
  m.serial_fraction = 0;
  EXPECT_DOUBLE_EQ(sim(p, s, m).makespan, 2);  // 8 s on 4 cores, no serial part
  m.serial_fraction = 1.0 / 3;                 // 4 / (1 + 3 · 1/3) = 2×
  EXPECT_DOUBLE_EQ(sim(p, s, m).makespan, 4);
  EXPECT_DOUBLE_EQ(sim(p, s, cores(4, 1)).makespan, 8);  // one core per task
}

TEST(ScheduleSim, MpiWorkersTakeNewTasksWhileRankZeroCommits) {
  // 1 node × 3 cores: rank 0 and 2 worker ranks; 4 independent tasks of 1 s, commits of 0.5 s
  // in turn on rank 0. Both workers finish at 1 and take tasks 3 and 4 at once (they were
  // ready), ending at 2; the commits run 1–1.5, 1.5–2, 2–2.5, 2.5–3.
  const std::vector<double> s{1, 1, 1, 1};
  const Plan p = plan_of(s, {{}, {}, {}, {}});
  ClusterModel m = cores(3);
  m.mpi = true;
  m.commit_seconds = 0.5;
  const ScheduleResult r = sim(p, s, m);
  EXPECT_EQ(r.workers, 2);
  EXPECT_DOUBLE_EQ(r.makespan, 3.0);
}

TEST(ScheduleSim, AnMpiDependentWaitsForItsInputsCommit) {
  // A chain t0 → t1 of 1 s each, commits of 0.5 s: t1 reads t0's committed record, so it starts
  // at 1.5, ends at 2.5, and its commit ends at 3. Each task's shipping (0.25 s on its worker)
  // adds to both: t0 ends at 1.25, commit to 1.75, t1 to 3.0, commit to 3.5. (Each task on one
  // worker: no borrowing of the idle one.)
  const std::vector<double> s{1, 1};
  const Plan p = plan_of(s, {{}, {0}});
  ClusterModel m = cores(3);
  m.mpi = true;
  m.widen = false;
  m.commit_seconds = 0.5;
  EXPECT_DOUBLE_EQ(sim(p, s, m).makespan, 3.0);
  m.mpi_task_seconds = 0.25;
  EXPECT_DOUBLE_EQ(sim(p, s, m).makespan, 3.5);
}

TEST(ScheduleSim, AnMpiWorkerBorrowsIdleWorkersOfItsNodeForACriticalChain) {
  // The plan of ACriticalChainIsWidened... on 1 node × 5 cores: rank 0 and 4 one-core workers.
  // t0 takes its worker and one idle worker of the node (2 cores: 3.75 s); the other two
  // workers run the small tasks as the 2 free cores did there: 4.75 s again, against 6 when
  // every task has one worker.
  std::vector<double> s(11, 1.0);
  s[0] = 6;
  Plan p = plan_of(s, std::vector<std::vector<int>>(11));
  for (size_t i = 1; i < s.size(); ++i) p.tasks[i].bytes = kThreadedTaskBytes / 2;
  ClusterModel m = cores(5);
  m.mpi = true;
  const ScheduleResult r = sim(p, s, m);
  EXPECT_EQ(r.workers, 4);
  EXPECT_DOUBLE_EQ(r.makespan, 4.75);
  m.widen = false;  // sirl plan's "without widening" line: one worker per task
  EXPECT_DOUBLE_EQ(sim(p, s, m).makespan, 6);
  m.widen = true;
  for (size_t i = 1; i < s.size(); ++i) p.tasks[i].bytes = 2 * kThreadedTaskBytes;
  p.tasks[0].bytes = kThreadedTaskBytes / 2;  // t0 in small steps: no worker lends it a core
  EXPECT_DOUBLE_EQ(sim(p, s, m).makespan, 6);
}

TEST(ScheduleSim, StreamingTasksShareTheirNodesBandwidth) {
  // Two 1 s tasks that each stream 10 GB alone (10 GB/s) on a 10 GB/s node: both at half speed,
  // 2 s; a third that streams nothing, on a third core, is not slowed.
  const std::vector<double> s{1, 1, 1};
  Plan p = plan_of(s, {{}, {}, {}});
  p.tasks[0].stream_bytes = p.tasks[1].stream_bytes = 10e9;
  ClusterModel m = cores(3);
  m.node_bandwidth = 10e9;
  const ScheduleResult r = sim(p, s, m);
  EXPECT_DOUBLE_EQ(r.makespan, 2);
  EXPECT_DOUBLE_EQ(r.bandwidth_stall, 2);  // each lost 1 s
  m.node_bandwidth = 0;                    // no limit
  EXPECT_DOUBLE_EQ(sim(p, s, m).makespan, 1);
  // On two nodes (MPI, 2 cores each: worker 0 on node 0 beside rank 0, workers 1 and 2 on node
  // 1) the equal-rank tasks go out in index order: t0 to node 0, t1 and t2 to node 1. Each node
  // then has one streaming task, within its bandwidth: nobody slows down.
  m.node_bandwidth = 10e9;
  m.mpi = true;
  m.nodes = 2;
  m.cores_per_node = 2;
  const ScheduleResult split = sim(p, s, m);
  EXPECT_EQ(split.workers, 3);
  EXPECT_DOUBLE_EQ(split.makespan, 1);
  EXPECT_DOUBLE_EQ(split.bandwidth_stall, 0);
}

TEST(ScheduleSim, RefusesImpossibleClusters) {
  const std::vector<double> s{1};
  const Plan p = plan_of(s, {{}});
  ClusterModel m = cores(2);
  m.nodes = 2;  // several nodes need MPI
  EXPECT_THROW(sim(p, s, m), std::invalid_argument);
  m = cores(1);
  m.mpi = true;  // rank 0 takes the only core
  EXPECT_THROW(sim(p, s, m), std::invalid_argument);
  m = cores(4);
  m.mpi = true;
  m.threads_per_worker = 8;  // wider than a node
  EXPECT_THROW(sim(p, s, m), std::invalid_argument);
}

// An offer of `free` of `total` cores with `ready_after` tasks still ready, for a task whose chain
// is `chain` FLOPs with `remaining` FLOPs of work left in all and `longest` the longest chain.
CoreOffer offer(int free, int total, int max_task_threads, size_t ready_after, double chain = 0,
                double remaining = 0, double longest = 0) {
  return {free, total, max_task_threads, ready_after, chain, remaining, longest};
}

TEST(TaskThreads, ExtraCoresOnlyWhenNothingElseIsReadyAndTheTaskIsBig) {
  Task big, small, narrow;
  big.flops = narrow.flops = 2 * kThreadedTaskFlops;
  big.bytes = small.bytes = 2 * kThreadedTaskBytes;
  small.flops = kThreadedTaskFlops / 2;
  narrow.bytes = kThreadedTaskBytes / 2;  // much work in small steps (GridRobot's φ)
  EXPECT_EQ(task_threads(big, offer(2, 2, 8, 0)), 2);
  EXPECT_EQ(task_threads(big, offer(6, 8, 4, 0)), 4);  // capped
  EXPECT_EQ(task_threads(big, offer(2, 2, 8, 1)), 1);  // another task is waiting
  EXPECT_EQ(task_threads(small, offer(2, 2, 8, 0)), 1);
  EXPECT_EQ(task_threads(narrow, offer(2, 2, 8, 0)), 1);
}

TEST(TaskThreads, ACriticalChainGetsTheFewestCoresThatFitItInItsShareOfTheWork) {
  Task big, narrow;
  big.flops = narrow.flops = 2 * kThreadedTaskFlops;
  big.bytes = 2 * kThreadedTaskBytes;
  narrow.bytes = kThreadedTaskBytes / 2;
  // 8 cores, 80 units of work left: a core's share is 10. A chain of 10 fits on one core.
  EXPECT_EQ(task_threads(big, offer(8, 8, 8, 3, 10, 80)), 1);
  // A chain of 20 needs a speed-up of 2: k / (1 + (k − 1)/4) is 1.6 at k = 2, 2 at k = 3.
  EXPECT_EQ(task_threads(big, offer(8, 8, 8, 3, 20, 80)), 3);
  EXPECT_DOUBLE_EQ(task_speedup(3, kAssumedSerialFraction), 2.0);
  // As many as are free or allowed, when that falls short.
  EXPECT_EQ(task_threads(big, offer(2, 8, 8, 3, 20, 80)), 2);
  EXPECT_EQ(task_threads(big, offer(8, 8, 1, 3, 20, 80)), 1);
  EXPECT_EQ(task_threads(big, offer(8, 8, 8, 3, 1000, 80)), 8);
  // A run cannot end before its longest chain does, even on max_task_threads cores: 100 on 8
  // (speed-up 8 / 2.75) takes 34.4, so a chain of 20 fits on one core after all, and the longest
  // chain itself takes all 8.
  EXPECT_EQ(task_threads(big, offer(8, 8, 8, 3, 20, 80, 100)), 1);
  EXPECT_EQ(task_threads(big, offer(8, 8, 8, 3, 100, 80, 100)), 8);
  EXPECT_EQ(task_threads(big, offer(8, 8, 8, 3, 20, 80, 20)), 3);  // 20 / 2.9 < 10: as above
  // Work in small steps stays on one core, critical or not.
  EXPECT_EQ(task_threads(narrow, offer(8, 8, 8, 3, 20, 80)), 1);
}

TEST(TaskThreads, TheSerialFractionFromASpeedUpIsAmdahlInverted) {
  // By hand: 2 cores at 1.6× is 2 / 1.6 − 1 = 0.25; 3 cores at 2× is (1.5 − 1) / 2 = 0.25;
  // 4 cores at 2.5× is (1.6 − 1) / 3 = 0.2.
  EXPECT_DOUBLE_EQ(serial_fraction_from_speedup(2, 1.6), 0.25);
  EXPECT_DOUBLE_EQ(serial_fraction_from_speedup(3, 2.0), 0.25);
  EXPECT_NEAR(serial_fraction_from_speedup(4, 2.5), 0.2, 1e-15);
  // Perfect or better scaling is no serial part; none, or a slowdown, is all serial.
  EXPECT_EQ(serial_fraction_from_speedup(2, 2.0), 0.0);
  EXPECT_EQ(serial_fraction_from_speedup(2, 2.3), 0.0);
  EXPECT_EQ(serial_fraction_from_speedup(2, 1.0), 1.0);
  EXPECT_EQ(serial_fraction_from_speedup(2, 0.8), 1.0);
  EXPECT_EQ(serial_fraction_from_speedup(1, 1.0), 1.0);
  EXPECT_EQ(serial_fraction_from_speedup(2, 0.0), 1.0);
  // task_speedup of the fraction found gives the speed-up back.
  for (int k : {2, 5, 64})
    for (double s : {0.0, 0.05, 0.3, 0.9})
      EXPECT_NEAR(serial_fraction_from_speedup(k, task_speedup(k, s)), s, 1e-12) << k << " " << s;
}

TEST(ScheduleSim, ACriticalChainIsWidenedWhileOtherTasksFillTheRestOfTheCores) {
  // 4 cores; t0 (6 s, big) and ten 1 s tasks in small steps (one core each). Work 16, a core's
  // share 4: t0 takes 2 cores (speed-up 1.6 at the model's serial fraction 0.25: 3.75 s). The
  // other two cores run small tasks at 0, 1, 2, 3 (eight of them, until 4); at 3.75 t0's two
  // cores take the last two, which end at 4.75. One core per task: t0 alone takes 6 s.
  std::vector<double> s(11, 1.0);
  s[0] = 6;
  Plan p = plan_of(s, std::vector<std::vector<int>>(11));
  for (size_t i = 1; i < s.size(); ++i) p.tasks[i].bytes = kThreadedTaskBytes / 2;
  EXPECT_DOUBLE_EQ(sim(p, s, cores(4, 4)).makespan, 4.75);
  EXPECT_DOUBLE_EQ(sim(p, s, cores(4, 1)).makespan, 6);
  ClusterModel narrow = cores(4, 4);
  narrow.widen = false;
  EXPECT_DOUBLE_EQ(sim(p, s, narrow).makespan, 6);
}

TEST(TaskThreads, TheSchedulerGivesALoneTaskTheFreeCoresAndNeverOversubscribes) {
  // t0 → {t1, t2}: t0 is alone (2 cores), then t1 and t2 are ready together (1 core each).
  const std::vector<double> s{1, 1, 1};
  const Plan p = plan_of(s, {{}, {0}, {0}});
  std::mutex mu;
  std::vector<int> got(3, 0);
  std::atomic<int> in_use{0}, peak{0};
  run_dag(p, std::vector<char>(3, 1), 2, 2, [&](int i, int k) {
    const int now = in_use += k;
    int old = peak.load();
    while (now > old && !peak.compare_exchange_weak(old, now)) {
    }
    {
      std::lock_guard lock(mu);
      got[size_t(i)] = k;
    }
    in_use -= k;
  });
  EXPECT_EQ(got, (std::vector<int>{2, 1, 1}));
  EXPECT_LE(peak.load(), 2);
}

TEST(TaskThreads, TheSchedulerWidensACriticalChainAsTheSimulatorDoes) {
  // The plan of ACriticalChainIsWidened...: t0 gets 2 of 4 cores, every other task one.
  std::vector<double> s(11, 1.0);
  s[0] = 6;
  Plan p = plan_of(s, std::vector<std::vector<int>>(11));
  for (size_t i = 1; i < s.size(); ++i) p.tasks[i].bytes = kThreadedTaskBytes / 2;
  std::mutex mu;
  std::vector<int> got(s.size(), 0);
  run_dag(p, std::vector<char>(s.size(), 1), 4, 4, [&](int i, int k) {
    std::lock_guard lock(mu);
    got[size_t(i)] = k;
  });
  std::vector<int> want(s.size(), 1);
  want[0] = 2;
  EXPECT_EQ(got, want);
}

TEST(TaskThreads, RunningTasksWorkingSetsStayWithinTheMemoryGiven) {
  // One 6 GB task (the highest rank) and eight of 1 GB on 4 cores with 7.5 GB: at most the big
  // one and one small one together, or four small ones; never the big one beside two.
  std::vector<double> s(9, 1.0);
  s[0] = 6;
  Plan p = plan_of(s, std::vector<std::vector<int>>(9));
  p.tasks[0].bytes = 6e9;
  for (size_t i = 1; i < s.size(); ++i) p.tasks[i].bytes = 1e9;
  std::mutex mu;
  double now = 0, peak = 0;
  int ran = 0;
  run_dag(
      p, std::vector<char>(s.size(), 1), 4, 1,
      [&](int i, int) {
        {
          std::lock_guard lock(mu);
          now += p.tasks[size_t(i)].bytes;
          peak = std::max(peak, now);
          ++ran;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(20));  // long enough to overlap
        std::lock_guard lock(mu);
        now -= p.tasks[size_t(i)].bytes;
      },
      7.5e9);
  EXPECT_EQ(ran, 9);
  EXPECT_LE(peak, 7.5e9);
  // A task larger than the memory given still runs, alone.
  p.tasks[0].bytes = 9e9;
  ran = 0;
  peak = now = 0;
  run_dag(
      p, std::vector<char>(s.size(), 1), 4, 1,
      [&](int i, int) {
        std::lock_guard lock(mu);
        now += p.tasks[size_t(i)].bytes;
        peak = std::max(peak, now);
        ++ran;
        now -= p.tasks[size_t(i)].bytes;
      },
      7.5e9);
  EXPECT_EQ(ran, 9);
}

}  // namespace
}  // namespace sirl
