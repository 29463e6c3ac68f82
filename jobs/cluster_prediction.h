// What a run of (part of) a plan will take on a cluster of this CPU: the simulated schedule
// (jobs/schedule_sim.h) over the calibrated task times, what happens outside the tasks, and the
// memory one node needs. `sirl plan --nodes/--mpi` prints it; `sirl submit` sizes a Slurm
// job's --time and --mem from the same numbers, so the two always agree.
#pragma once
#include <vector>

#include "experiment/plan.h"
#include "jobs/estimate.h"
#include "jobs/schedule_sim.h"

namespace sirl {

struct ClusterPrediction {
  ScheduleResult schedule;  // the engine's scheduling rules
  ScheduleResult narrow;    // every task on one core (threads) or one worker rank (MPI)
  // Building Ξ and the query bundles (once per process; under MPI in the worker ranks and once
  // more on rank 0), writing the results file, starting MPI.
  double outside_seconds = 0;
  double wall_seconds = 0;  // schedule.makespan + outside_seconds
  // The busiest node's memory: each process's datasets plus the working sets of the largest
  // tasks that can run at once there (one per core for threads, one per worker rank for MPI).
  double memory_bytes_per_node = 0;
};

// `tasks`: which of the plan's tasks the run computes (a shard's, or all). Throws
// std::invalid_argument for an impossible model (schedule_sim.h).
ClusterPrediction predict_cluster(const Plan& plan, const PlanEstimate& e, const ClusterModel& m,
                                  const std::vector<char>& tasks);

}  // namespace sirl
