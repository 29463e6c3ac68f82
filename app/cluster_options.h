// What `sirl plan` and `sirl submit` are told about a cluster, and the model both predict it
// with: so a plan and a submission of the same profile on the same cluster agree on time and
// memory.
#pragma once
#include <string>

#include "experiment/profile.h"
#include "jobs/schedule_sim.h"

namespace sirl::app {

// A cluster (--nodes, --mpi, ...), with this machine's defaults where the user says nothing.
struct PlanClusterOptions {
  int nodes = 1, cores_per_node = 0, threads_per_worker = 1, task_threads = 0;
  bool mpi = false;
  double node_bandwidth_gbs = 0, serial_fraction = kMeasuredSerialFraction;
};

ClusterModel cluster_model(const PlanClusterOptions& o);

// A profile by name or path with the command's --set overrides; a bad one is a UsageError.
Profile load_or_usage(const std::string& name);
// This machine's cores.
int default_threads();

}  // namespace sirl::app
