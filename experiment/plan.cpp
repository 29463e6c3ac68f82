#include "experiment/plan.h"

#include "experiment/simulation_tasks.h"
#include "experiment/study_tasks.h"

namespace sirl {

Plan make_plan(const Profile& p) {
  Plan plan;
  add_simulation_tasks(plan, p);  // experiment/simulation_plan.cpp
  add_study_tasks(plan, p);       // experiment/study_tasks.cpp
  return plan;
}

}  // namespace sirl
