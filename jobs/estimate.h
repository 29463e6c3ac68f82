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
  double setup_seconds = 0;   // Σ over environments of Ξ + its seeds' bundles, one core
  std::vector<char> pending;  // the tasks the times above count (the rest are in a cache)
  // The calibration is timed in CPU time: the rates are an idle core's. cpu_share is the share of
  // a core it got (CPU / wall time; well below 1 when the machine was busy), load_average the
  // 1-minute load when it ended: a busy machine runs slower than predicted.
  double cpu_share = 1;
  double load_average = 0;
  double calibration_wall_seconds = 0, calibration_cpu_seconds = 0;  // Σ over its timings
};

// One line on how busy the machine was while calibrating and what that means for the prediction
// (for `threads` cores), or "" when it had the cores to itself.
std::string busy_machine_note(const PlanEstimate& e, int threads);

// Calibrates the rates (short runs of real training) and simulates the thread scheduler
// on `threads` cores (a big task takes several cores when nothing else is ready or its chain is
// critical, as `sirl run` does). `pending` (empty: every task) marks the tasks still to run: only
// their rate classes are calibrated, and seconds, seconds_one_thread and peak_bytes count only
// them (a task a cache holds costs its run nothing); task_seconds covers every task.
PlanEstimate estimate_plan(const Plan& plan, const Profile& p, int threads,
                           std::vector<char> pending = {});

}  // namespace sirl
