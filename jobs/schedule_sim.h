// Predicts a run's makespan by replaying the engine's own scheduling over estimated task times:
// the ready queue by upward rank (jobs/ready_queue.h), the thread scheduler's cores-per-task
// rule (task_threads in jobs/scheduler.h), or the MPI dispatcher's pull model with rank 0
// committing every result in turn (jobs/mpi_run.h). Main-memory bandwidth is shared per node: a
// task that streams its weights and Adam moments (Task::stream_bytes) slows down when the
// streaming tasks of its node ask for more than the node delivers.
#pragma once
#include <string>
#include <vector>

#include "experiment/plan.h"
#include "jobs/scheduler.h"  // task_speedup

namespace sirl {

struct ClusterModel {
  int nodes = 1;
  int cores_per_node = 1;
  // MPI: rank 0 dispatches and commits (one core that runs no task), every other core is a
  // worker rank of `threads_per_worker` cores. Without MPI (one node): the thread scheduler,
  // whose tasks may take several cores (task_threads: nothing else ready, or a critical chain;
  // at most max_task_threads).
  bool mpi = false;
  int threads_per_worker = 1;  // MPI only
  int max_task_threads = 1;    // threads only: the most cores one task takes
  // Speed-up of one task on k cores: k / (1 + serial_fraction · (k − 1)) (Amdahl). What the
  // machine does (measured: kMeasuredSerialFraction); the scheduler sizes critical chains with its
  // own kAssumedSerialFraction, a rule rather than a model of the machine.
  double serial_fraction = kMeasuredSerialFraction;
  double commit_seconds = 0.002;  // per task: in the worker (threads), on rank 0 (MPI)
  // Outside the schedule (measured with smoke's 336 tasks): reading every
  // committed record back and writing the results file at the end, per task; and what
  // `mpirun` adds to a run (MPI_Init, the workers' hello, MPI_Finalize).
  double finish_seconds_per_task = 0.0025;
  double mpi_start_seconds = 0.4;
  // MPI, per task on its worker: receiving it, reading its inputs' records from the shared
  // staging folder (threads keep them in memory), serialising and sending its record.
  double mpi_task_seconds = 0.004;
  double node_bandwidth = 0;  // bytes/s of main memory per node; 0: not a limit
  // The engine's rule (task_threads) widens big tasks; false: every task on one core (threads)
  // or one worker rank (MPI), to show what widening buys.
  bool widen = true;
};

struct ScheduleResult {
  double makespan = 0;             // seconds from the first task's start to the last commit
  double core_seconds = 0;         // Σ over tasks of (cores held × seconds held)
  double utilisation = 0;          // core_seconds / (makespan × cores that run tasks)
  double bandwidth_stall = 0;      // seconds lost to the bandwidth limit, summed over tasks
  std::vector<int> critical_path;  // the longest chain of estimated task times, first to last
  double critical_path_seconds = 0;
  int workers = 0;  // task slots: cores (threads) or worker ranks (MPI)
};

// seconds[i]: task i alone on one core. Pending tasks only (a dependency not pending is done).
// Throws std::invalid_argument for an impossible model (no worker, a worker wider than a node).
ScheduleResult simulate_schedule(const Plan& plan, const std::vector<double>& seconds,
                                 const std::vector<char>& pending, const ClusterModel& m);

}  // namespace sirl
