// `sirl plan`: what a profile will cost on this machine, without running it. Rates come from a
// short calibration run of the real training code for each rate class its tasks name
// (experiment/calibration.h), each timed at two lengths.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "experiment/plan.h"
#include "experiment/profile.h"

namespace sirl {

struct PlanEstimate {
  std::map<std::string, double> gflops_per_s;  // measured rate per "env/class" on one thread
  std::map<std::string, double> call_seconds;  // what one call costs beyond its FLOPs, per kind
  std::vector<double> task_seconds;  // each task alone on one core: flops / rate + call cost
  double seconds_one_thread = 0;     // Σ task_seconds + commits
  double seconds = 0;     // the thread scheduler on `threads` cores, simulated (schedule_sim.h)
  double peak_bytes = 0;  // datasets + the `threads` largest working sets
  double data_bytes = 0;  // the datasets every process holds (Ξ's inputs and features)
  // What a run spends outside its tasks, per environment: building Ξ (timed on a small Ξ and
  // scaled by the trajectory count) and one seed's query bundle. A run builds each once, inside
  // the first task that reads it; under MPI every worker rank builds what its tasks read, and
  // rank 0 builds them for the results file beside the dispatching.
  std::map<std::string, double> dataset_seconds, bundle_seconds;
  double setup_seconds = 0;  // Σ over environments of Ξ + its seeds' bundles, one core
};

// Calibrates the rates (short runs of real training) and simulates the thread scheduler
// on `threads` cores (a big task takes several cores when nothing else is ready or its chain is
// critical, as `sirl run` does).
PlanEstimate estimate_plan(const Plan& plan, const Profile& p, int threads);

}  // namespace sirl
