// sirl plan's estimate and the cost model behind it.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/simulation_tasks.h"
#include "jobs/estimate.h"
#include "tests/small_profile.h"

namespace sirl {
namespace {

// sirl plan's estimate: each task takes its FLOPs over its kind's measured rate plus 2 ms, the
// one-thread total is their sum, and the parallel time lies between total/threads and the total.
TEST(Estimate, AddsEachTasksFlopsOverItsKindsRate) {
  const Profile p = parse_profile(test::kSmallProfile, "t.toml");
  const Plan plan = make_plan(p);
  const PlanEstimate e = estimate_plan(plan, p, 2);
  double total = 0;
  for (const auto& t : plan.tasks) {
    std::string kind = t.kind.name();
    if (t.kind == rep_kind()) kind = t.variant.method == Method::sirl ? "rep_sirl" : "rep_pref";
    if (t.kind == tpa_kind()) kind = t.frozen ? "tpa_frozen" : "tpa_unfrozen";
    if (t.kind == linear_tpa_kind()) kind = "fpe";  // timed at the probe's rate
    const auto it = e.gflops_per_s.find(t.env + "/" + kind);
    const double rate = it == e.gflops_per_s.end() ? 1e9 : std::max(it->second, 1e-3) * 1e9;
    const auto once = e.call_seconds.find(t.env + "/" + kind);
    total += t.flops / rate + (once == e.call_seconds.end() ? 0.0 : once->second) + 0.002;
  }
  for (const char* k : {"grid/rep_sirl", "grid/rep_pref", "grid/vae", "grid/tpa_frozen"})
    EXPECT_GT(e.gflops_per_s.at(k), 0.01) << k;  // measured, not the default
  for (const auto& [k, c] : e.call_seconds) EXPECT_GE(c, 0) << k;
  EXPECT_NEAR(e.seconds_one_thread, total, 1e-9 * total);
  EXPECT_GE(e.seconds, total / 2 - 1e-9);
  EXPECT_LE(e.seconds, total + 1e-9);
  EXPECT_GT(e.peak_bytes, 0);
}

// `sirl plan --cache`: tasks a cache holds cost the run nothing. With every task but the FPE
// cells held, the one-thread total is the FPE cells' alone, and only their rate is calibrated.
TEST(Estimate, CountsOnlyThePendingTasks) {
  const Profile p = parse_profile(test::kSmallProfile, "t.toml");
  const Plan plan = make_plan(p);
  std::vector<char> pending(plan.tasks.size(), 0);
  for (size_t i = 0; i < plan.tasks.size(); ++i) pending[i] = plan.tasks[i].kind == fpe_kind();
  const PlanEstimate e = estimate_plan(plan, p, 2, pending);
  double total = 0;
  for (size_t i = 0; i < plan.tasks.size(); ++i)
    if (pending[i]) total += e.task_seconds[i] + 0.002;  // + one commit each
  EXPECT_NEAR(e.seconds_one_thread, total, 1e-9 * total);
  EXPECT_LE(e.seconds, total + 1e-9);
  EXPECT_TRUE(e.gflops_per_s.count("grid/fpe"));
  EXPECT_FALSE(e.gflops_per_s.count("grid/rep_sirl")) << "calibrated a class no pending task has";
  EXPECT_FALSE(e.gflops_per_s.count("grid/tpa_frozen"));
}

TEST(Estimate, CostModelCountsTheFlopsByHand) {
  const Plan plan = make_plan(parse_profile(test::kSmallProfile, "t.toml"));
  // φ 19→128→128→6: 2·(19·128 + 128·128 + 128·6) = 39,168 FLOPs per sample forward.
  const double phi = 2.0 * (19 * 128 + 128 * 128 + 128 * 6);
  // SIRL at N = 100 for 7 epochs: 3 (fwd + bwd) × 3N samples × epochs, plus embedding Ξ (1960).
  EXPECT_DOUBLE_EQ(plan.tasks[plan.index.at("grid/s0/sirl/N100/rep")].flops,
                   3 * phi * 300 * 7 + phi * 1960);
  // Random trains nothing: only the embedding of Ξ.
  EXPECT_DOUBLE_EQ(plan.tasks[plan.index.at("grid/s0/random/rep")].flops, phi * 1960);
  // A frozen TPA cell, head 6→32→16→1 (1,440 FLOPs forward), 20 heads × 2M = 20 samples × 500.
  const double head = 2.0 * (6 * 32 + 32 * 16 + 16 * 1);
  EXPECT_DOUBLE_EQ(plan.tasks[plan.index.at("grid/s0/sirl/N100/tpa/M10/frozen")].flops,
                   20 * 3 * head * 20 * 500);
}

}  // namespace
}  // namespace sirl
