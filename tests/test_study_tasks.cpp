// experiment/study_tasks: the user study as task kinds of the plan. Run through the batch engine
// (tasks on two threads, committed, assembled from the results file), it must give exactly the
// numbers `sirl study analyze` computes in one call on the same cohort.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <stdexcept>

#include "engine/study_analysis.h"
#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/study_tasks.h"
#include "jobs/run.h"
#include "results/results_file.h"
#include "tests/scratch_dir.h"

namespace sirl {
namespace {

const char* kStudyProfile = R"(
name = "study-tasks"
envs = ["grid"]
seeds = [0]
[study]
env = "grid"
users = 3
similarity = 30
preference = 12
epochs = 4
tpa_epochs = 4
seeds = 2
splits = 3
)";

void expect_same(const std::vector<double>& a, const std::vector<double>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i]) && std::isnan(b[i])) continue;
    EXPECT_EQ(a[i], b[i]) << what << "[" << i << "]";
  }
}

TEST(StudyTasks, ThePlanHasOneTaskPerPieceWithItsDependencies) {
  const Profile p = parse_profile(kStudyProfile, "study.toml");
  const Plan plan = make_plan(p);
  // 2 seeds × (SIRL, Random), per user a Held-out φ and a TPA task, one simulated-TPA task.
  EXPECT_EQ(plan.count(study_rep_kind()), 4);
  EXPECT_EQ(plan.count(study_heldout_kind()), 3);
  EXPECT_EQ(plan.count(study_tpa_kind()), 3);
  EXPECT_EQ(plan.count(study_simulated_kind()), 1);
  EXPECT_EQ(plan.count(study_analysis_kind()), 1);
  EXPECT_EQ(int(plan.tasks.size()), 12);  // no grid cells: the profile has only [study]
  for (const auto& t : plan.tasks) {
    if (t.kind == study_analysis_kind()) {
      // It reads each seed's SIRL and Random, each participant's TPA and the simulated TPA, and
      // trains nothing.
      EXPECT_EQ(t.flops, 0);
      std::set<std::string> deps;
      for (int d : t.deps) deps.insert(plan.tasks[d].key);
      EXPECT_EQ(deps, (std::set<std::string>{
                          "study/s0/sirl/rep", "study/s0/random/rep", "study/s1/sirl/rep",
                          "study/s1/random/rep", "study/tpa/" + simulated_participant_id(0),
                          "study/tpa/" + simulated_participant_id(1),
                          "study/tpa/" + simulated_participant_id(2), "study/simulated"}));
      continue;
    }
    EXPECT_GT(t.flops, 0) << t.key;
    if (t.kind == study_tpa_kind()) {
      ASSERT_EQ(t.deps.size(), 3u);
      EXPECT_EQ(plan.tasks[t.deps[0]].key, "study/s0/sirl/rep");
      EXPECT_EQ(plan.tasks[t.deps[1]].key, "study/s0/random/rep");
      EXPECT_EQ(plan.tasks[t.deps[2]].key, "study/heldout/" + t.participant + "/rep");
    }
  }
}

TEST(StudyTasks, TasksGiveExactlyTheOneCallAnalysis) {
  const Profile p = parse_profile(kStudyProfile, "study.toml");
  const test::ScratchDir scratch;
  const std::string out = scratch.file("study.h5");
  RunOptions o;
  o.out = out;
  o.threads = 2;
  o.quiet = true;
  const RunSummary s = run_profile(p, o);
  EXPECT_EQ(s.ran, 12);
  const std::vector<TaskRecord> records = read_results_records(out);
  const StudyAnalysis tasks = assemble_study(p, records);

  const Study cohort = simulate_cohort(p.study.cohort);
  StudyAnalysisConfig c = study_config(p);
  c.threads = 2;  // thread count must not matter
  const StudyAnalysis one = analyze_study(cohort, study_dataset(cohort), c);

  EXPECT_EQ(tasks.triplets, one.triplets);
  EXPECT_EQ(tasks.triplets, 3 * 30);
  EXPECT_EQ(tasks.participants, one.participants);
  EXPECT_EQ(tasks.both_features, one.both_features);
  expect_same(tasks.fpe_sirl, one.fpe_sirl, "fpe_sirl");
  expect_same(tasks.fpe_random, one.fpe_random, "fpe_random");
  expect_same(tasks.real_sirl, one.real_sirl, "real_sirl");
  expect_same(tasks.real_random, one.real_random, "real_random");
  expect_same(tasks.real_random_other, one.real_random_other, "real_random_other");
  expect_same(tasks.heldout_sirl, one.heldout_sirl, "heldout_sirl");
  expect_same(tasks.simulated_sirl, one.simulated_sirl, "simulated_sirl");
  expect_same(tasks.simulated_random, one.simulated_random, "simulated_random");
  expect_same(tasks.simulated_random_other, one.simulated_random_other, "simulated_random_other");
  // Not vacuous: every participant was analysed and SIRL's FPE is a real number per seed.
  EXPECT_EQ(tasks.participants.size(), 3u);
  ASSERT_EQ(tasks.fpe_sirl.size(), 2u);
  EXPECT_GT(tasks.fpe_sirl[0], 0);

  // /tables/study, what `sirl reproduce` draws Fig. 6 from: one row per value, and the values of
  // each (measure, method) in order are the one-call analysis' (participant rows named by id).
  const ResultTables all_tables = result_tables(records);
  const H5Table& table = all_tables.at("study");
  auto col = [&](const std::string& name) -> const H5Table::Column& {
    for (const auto& c : table.columns)
      if (c.name == name) return c;
    throw std::out_of_range(name);
  };
  std::map<std::string, std::vector<double>> values;
  std::vector<std::string> real_units;
  for (size_t i = 0; i < table.rows(); ++i) {
    const std::string measure = col("measure").strings[i], method = col("method").strings[i];
    values[measure + "_" + method].push_back(col("value").doubles[i]);
    if (measure == "real" && method == "sirl") real_units.push_back(col("unit").strings[i]);
    EXPECT_EQ(col("triplets").ints[i], one.triplets);
    EXPECT_EQ(col("random_mode").strings[i], "unfrozen");
  }
  EXPECT_EQ(table.rows(), 2u * 2 + 3u * 6 + 3u * one.simulated_sirl.size());
  EXPECT_EQ(real_units, one.participants);
  expect_same(values["fpe_sirl"], one.fpe_sirl, "table fpe sirl");
  expect_same(values["fpe_random"], one.fpe_random, "table fpe random");
  expect_same(values["real_sirl"], one.real_sirl, "table real sirl");
  expect_same(values["real_random"], one.real_random, "table real random");
  expect_same(values["real_random_other"], one.real_random_other, "table real random_other");
  expect_same(values["heldout_sirl"], one.heldout_sirl, "table heldout sirl");
  expect_same(values["heldout_random"], one.heldout_random, "table heldout random");
  expect_same(values["simulated_sirl"], one.simulated_sirl, "table simulated sirl");
  expect_same(values["simulated_random_other"], one.simulated_random_other, "table sim other");

  // A rerun finds every task committed and computes nothing.
  EXPECT_EQ(run_profile(p, o).ran, 0);
}

}  // namespace
}  // namespace sirl
