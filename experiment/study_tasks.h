// The user study (paper §5) as task kinds of the plan, so it gets commits, resume, MPI and a line
// in `sirl plan` like every other task. The cohort is simulated from [study] (RunContext::study);
// the tasks are the pieces of engine/study_analysis.h:
//   study/s<k>/{sirl,random}/rep  SIRL on the pooled triplets / Random, training seed k, + FPE
//   study/heldout/<id>/rep        SIRL without participant <id>'s triplets
//   study/tpa/<id>                Real and Held-out TPA on <id>'s own preferences
//   study/simulated               TPA on simulated perfect preferences
//   study/analysis                the analysis from all of these, as the long table /tables/study
// assemble_study puts the committed records back together into the analysis `sirl study
// analyze` computes in one call (the same numbers: tests/test_study_tasks.cpp); the analysis
// task writes it as rows, so `sirl reproduce` only draws Fig. 6 from the results file.
#pragma once
#include <vector>

#include "engine/study_analysis.h"
#include "experiment/profile.h"
#include "experiment/task.h"
#include "experiment/task_kinds.h"
#include "results/task_record.h"

namespace sirl {

// The analysis settings of a profile's [study] (one thread per task: tasks run in parallel).
StudyAnalysisConfig study_config(const Profile& p);

// Adds the study's tasks to the plan (when [study] is there).
void add_study_tasks(Plan& plan, const Profile& p);

// The four kinds' declarations (experiment/task_kinds.h).
const TaskKindSpec& study_rep_kind();
const TaskKindSpec& study_heldout_kind();
const TaskKindSpec& study_tpa_kind();
const TaskKindSpec& study_simulated_kind();
const TaskKindSpec& study_analysis_kind();

// The analysis from the study tasks' records. Throws std::runtime_error naming a missing task.
StudyAnalysis assemble_study(const Profile& p, const std::vector<TaskRecord>& records);
// The same from the analysis' configuration and the cohort's size (what the analysis task's
// runner has: experiment/task_config.h).
StudyAnalysis assemble_study(const StudyAnalysisConfig& c, int users,
                             const std::vector<TaskRecord>& records);

}  // namespace sirl
