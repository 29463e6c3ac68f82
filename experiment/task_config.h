// What a task's runner reads besides its inputs' outputs and the shared data of its run
// (RunContext: Ξ, the query bundles, the study's cohort): compiled once from the profile when the
// task is planned (add_task, by its kind's `compile`), immutable afterwards, shared by every copy
// of the task. Runners never see the Profile, so what a runner reads is exactly what was compiled
// here, and the digest's text (`settings`) is compiled in the same step from the same profile.
#pragma once
#include <optional>
#include <string>

#include "engine/active_queries.h"
#include "engine/hyperparams.h"
#include "engine/study_analysis.h"
#include "experiment/profile.h"

namespace sirl {

struct TaskConfig {
  // The kind's canonical text of what it reads of the profile (TaskKindSpec::settings): with the
  // task's key, fields and inputs' digests, its content digest (experiment/task_digest.h).
  std::string settings;
  // Whether its networks multiply in bf16 (TaskKindSpec::bf16_products): the CPU class its bits
  // belong to.
  bool bf16_products = false;
  // Its environment's hyper-parameters at its point (a TPA cell's with its method's stop rule);
  // absent for kinds that read none.
  std::optional<Hyper> hyper;
  // A noisy teacher's cell (Task::teacher not empty): the teacher's axis and level.
  std::optional<TeacherPoint> teacher;
  // A representation of an external method: its declaration ([external.<name>]).
  std::optional<ExternalMethod> external;
  // An active task: its rounds, rule, budget and hyper-parameters.
  std::optional<ActiveConfig> active;
  // A study task: the analysis' configuration (threads 1; the runner gives the task's cores), and
  // the cohort's size the analysis assembles.
  std::optional<StudyAnalysisConfig> study;
  int study_users = 0;
};

}  // namespace sirl
