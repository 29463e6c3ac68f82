// The task-kind registry: each kind declared once, its key scheme telling every cell apart, and
// add_task deriving keys, inputs and costs from it.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/simulation_tasks.h"
#include "experiment/task_kinds.h"
#include "tests/small_profile.h"

namespace sirl {
namespace {

TEST(TaskKinds, EveryKindIsRegisteredOnceByNameWithItsOwnTable) {
  std::vector<std::string> names;
  std::set<std::string> tables;
  for (const TaskKindSpec* k : task_kinds()) {
    names.push_back(k->name);
    if (!k->table.name.empty()) {
      EXPECT_TRUE(tables.insert(k->table.name).second) << k->table.name;
      EXPECT_EQ(k->table.kind, k->name);  // a kind's table reads that kind's records
    }
  }
  // Each kind's file registered it, in name order, whatever order the files were linked in.
  EXPECT_EQ(names, (std::vector<std::string>{"active", "fpe", "rep", "robust_fpe", "robust_tpa",
                                             "study_analysis", "study_heldout", "study_rep",
                                             "study_simulated", "study_tpa", "tpa", "tpa_linear",
                                             "vae"}));
  EXPECT_EQ(tables, (std::set<std::string>{"fpe", "tpa", "robust_fpe", "robust_tpa", "study"}));
  EXPECT_STREQ(TaskKind(tpa_kind()).name(), "tpa");
  EXPECT_TRUE(TaskKind(tpa_kind()) == tpa_kind());
  EXPECT_FALSE(TaskKind(tpa_kind()) == robust_tpa_kind());  // a copy of tpa's, another kind
  EXPECT_THROW(TaskKind().name(), std::logic_error);        // a task whose kind was never set
}

TEST(TaskKinds, ARegistrationWithAFunctionMissingOrANameTakenIsRefused) {
  TaskKindSpec copy = fpe_kind();  // "fpe" is registered already
  EXPECT_THROW(TaskKindRegistration{copy}, std::logic_error);
  copy.name = "fpe_without_runner";
  copy.run = nullptr;
  EXPECT_THROW(TaskKindRegistration{copy}, std::logic_error);
  copy.run = fpe_kind().run;
  copy.complete_fields = nullptr;  // an upgrade test without its step
  EXPECT_THROW(TaskKindRegistration{copy}, std::logic_error);
  EXPECT_EQ(task_kinds().size(), 13u);  // nothing was added
}

// Two TPA cells that differ in one field are two tasks: a key scheme that dropped a field would
// merge them silently (one cell's result reported for both).
TEST(TaskKinds, TheKeySchemeTellsApartCellsThatDifferInAnyField) {
  const Task base = [] {
    Task t = experiment_cell(tpa_kind(), "grid", 0, Variant{Method::sirl, false}, 100);
    t.M = 10;
    return t;
  }();
  auto key = [](const Task& t) { return t.kind.spec().key(t); };
  std::set<std::string> keys{key(base)};
  auto differs = [&](auto change) {
    Task t = base;
    change(t);
    EXPECT_TRUE(keys.insert(key(t)).second) << key(t);
  };
  differs([](Task& t) { t.env = "jaco"; });
  differs([](Task& t) { t.seed = 1; });
  differs([](Task& t) { t.variant.vae = true; });
  differs([](Task& t) { t.variant.method = Method::multipref10; });
  differs([](Task& t) { t.N = 200; });
  differs([](Task& t) { t.M = 20; });
  differs([](Task& t) { t.frozen = false; });
  differs([](Task& t) { t.kind = fpe_kind(); });
  differs([](Task& t) { t.teacher = "beta=1"; });
  EXPECT_EQ(key(base), "grid/s0/sirl/N100/tpa/M10/frozen");
  EXPECT_EQ(key(experiment_cell(robust_fpe_kind(), "grid", 0, base.variant, 100, "beta=1")),
            "grid/s0/beta=1/sirl/N100/fpe");
  // Methods without queries share one φ whatever N the cell names.
  EXPECT_EQ(experiment_cell(fpe_kind(), "grid", 0, Variant{Method::random, false}, 100).N, 0);
}

// add_task keys the task, adds what it reads first (SIRL+VAE's φ, and the VAE before that), wires
// the dependencies and sets the cost; a second add of the same cell adds nothing.
TEST(TaskKinds, AddTaskAddsTheInputsFirstAndEachTaskOnce) {
  const Profile p = parse_profile(test::kSmallProfile, "t.toml");
  Plan plan;
  const Variant v{Method::sirl, true};
  Task cell = experiment_cell(tpa_kind(), "grid", 1, v, 100);
  cell.M = 10;
  const int i = add_task(plan, p, cell);
  ASSERT_EQ(plan.tasks.size(), 3u);
  EXPECT_EQ(plan.tasks[0].key, "grid/s1/vae");
  EXPECT_EQ(plan.tasks[1].key, "grid/s1/sirl+vae/N100/rep");
  EXPECT_EQ(plan.tasks[1].deps, (std::vector<int>{0}));
  EXPECT_EQ(plan.tasks[2].deps, (std::vector<int>{1}));
  EXPECT_EQ(i, 2);
  for (const Task& t : plan.tasks) EXPECT_GT(t.flops, 0) << t.key;
  EXPECT_EQ(add_task(plan, p, cell), 2);
  EXPECT_EQ(add_task(plan, p, experiment_cell(fpe_kind(), "grid", 1, v, 100)), 3);
  EXPECT_EQ(plan.tasks.size(), 4u);  // the FPE cell reuses the φ and the VAE
  EXPECT_EQ(plan.tasks[3].deps, (std::vector<int>{1}));
  for (const auto& [key, at] : plan.index) EXPECT_EQ(plan.tasks[size_t(at)].key, key);
}

}  // namespace
}  // namespace sirl
