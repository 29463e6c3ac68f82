#include "jobs/cluster_prediction.h"

#include <algorithm>
#include <functional>

namespace sirl {

ClusterPrediction predict_cluster(const Plan& plan, const PlanEstimate& e, const ClusterModel& m,
                                  const std::vector<char>& tasks) {
  ClusterPrediction r;
  r.schedule = simulate_schedule(plan, e.task_seconds, tasks, m);
  ClusterModel one = m;
  one.widen = false;
  r.narrow = simulate_schedule(plan, e.task_seconds, tasks, one);
  size_t count = 0;
  std::vector<double> sizes;
  for (size_t i = 0; i < plan.tasks.size(); ++i)
    if (tasks[i]) ++count, sizes.push_back(plan.tasks[i].bytes);
  r.outside_seconds = e.setup_seconds * (m.mpi ? 2 : 1) +
                      m.finish_seconds_per_task * double(count) + (m.mpi ? m.mpi_start_seconds : 0);
  r.wall_seconds = r.schedule.makespan + r.outside_seconds;
  // Processes on the busiest node (node 0: under MPI it also holds rank 0) and how many tasks
  // run there at once.
  const int processes =
      m.mpi ? std::max(1, m.cores_per_node / std::max(1, m.threads_per_worker)) : 1;
  const int at_once = m.mpi ? std::max(1, processes - (m.nodes == 1 ? 1 : 0)) : m.cores_per_node;
  std::sort(sizes.begin(), sizes.end(), std::greater<>());
  r.memory_bytes_per_node = e.data_bytes * processes;
  for (int k = 0; k < at_once && k < int(sizes.size()); ++k) r.memory_bytes_per_node += sizes[k];
  return r;
}

}  // namespace sirl
