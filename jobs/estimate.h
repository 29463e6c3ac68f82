// `sirl plan`: what a profile will cost on this machine, without running it. Rates come from a
// short calibration run of the real training code for each task kind (about a second).
#pragma once
#include <map>
#include <string>

#include "jobs/plan.h"
#include "jobs/profile.h"

namespace sirl {

struct PlanEstimate {
  std::map<std::string, double> gflops_per_s;  // measured rate per "env/kind" on one thread
  double seconds_one_thread = 0;               // Σ task flops / rate
  double seconds = 0;                          // with `threads` workers (tasks in parallel)
  double peak_bytes = 0;                       // datasets + the `threads` largest working sets
};

PlanEstimate estimate_plan(const Plan& plan, const Profile& p, int threads);

}  // namespace sirl
