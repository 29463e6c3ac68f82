// The task-kind registry: each kind declared once, its key scheme telling every cell apart, and
// add_task deriving keys, inputs and costs from it.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "jobs/plan.h"
#include "jobs/profile.h"
#include "jobs/simulation_tasks.h"
#include "jobs/task_kinds.h"
#include "tests/small_profile.h"

namespace sirl {
namespace {

TEST(TaskKinds, EachKindIsRegisteredOnceInOrderWithItsOwnNameAndTable) {
  std::set<std::string> names, tables;
  for (size_t i = 0; i < task_kinds().size(); ++i) {
    const TaskKindSpec& k = task_kinds()[i];
    EXPECT_EQ(size_t(k.kind), i) << k.name;
    EXPECT_TRUE(names.insert(k.name).second) << k.name;
    if (!k.table.name.empty()) {
      EXPECT_TRUE(tables.insert(k.table.name).second) << k.table.name;
      EXPECT_EQ(k.table.kind, k.name);  // a kind's table reads that kind's records
    }
  }
  EXPECT_EQ(tables, (std::set<std::string>{"fpe", "tpa", "robust_fpe", "robust_tpa"}));
}

// Two TPA cells that differ in one field are two tasks: a key scheme that dropped a field would
// merge them silently (one cell's result reported for both).
TEST(TaskKinds, TheKeySchemeTellsApartCellsThatDifferInAnyField) {
  const Task base = [] {
    Task t = experiment_cell(TaskKind::tpa, "grid", 0, Variant{Method::sirl, false}, 100);
    t.M = 10;
    return t;
  }();
  auto key = [](const Task& t) { return task_kind(t.kind).key(t); };
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
  differs([](Task& t) { t.kind = TaskKind::fpe; });
  differs([](Task& t) { t.teacher = "beta=1"; });
  EXPECT_EQ(key(base), "grid/s0/sirl/N100/tpa/M10/frozen");
  EXPECT_EQ(key(experiment_cell(TaskKind::robust_fpe, "grid", 0, base.variant, 100, "beta=1")),
            "grid/s0/beta=1/sirl/N100/fpe");
  // Methods without queries share one φ whatever N the cell names.
  EXPECT_EQ(experiment_cell(TaskKind::fpe, "grid", 0, Variant{Method::random, false}, 100).N, 0);
}

// add_task keys the task, adds what it reads first (SIRL+VAE's φ, and the VAE before that), wires
// the dependencies and sets the cost; a second add of the same cell adds nothing.
TEST(TaskKinds, AddTaskAddsTheInputsFirstAndEachTaskOnce) {
  const Profile p = parse_profile(test::kSmallProfile, "t.toml");
  Plan plan;
  const Variant v{Method::sirl, true};
  Task cell = experiment_cell(TaskKind::tpa, "grid", 1, v, 100);
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
  EXPECT_EQ(add_task(plan, p, experiment_cell(TaskKind::fpe, "grid", 1, v, 100)), 3);
  EXPECT_EQ(plan.tasks.size(), 4u);  // the FPE cell reuses the φ and the VAE
  EXPECT_EQ(plan.tasks[3].deps, (std::vector<int>{1}));
  for (const auto& [key, at] : plan.index) EXPECT_EQ(plan.tasks[size_t(at)].key, key);
}

}  // namespace
}  // namespace sirl
