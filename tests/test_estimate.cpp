// sirl plan's estimate and the cost model behind it.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/simulation_tasks.h"
#include "jobs/calibration_cache.h"
#include "jobs/estimate.h"
#include "tests/scratch_dir.h"
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

// SIRL_CALIBRATION_CACHE set for one test, unset after it.
struct KeptCalibrations {
  test::ScratchDir dir{"sirl_cal"};
  KeptCalibrations() { setenv("SIRL_CALIBRATION_CACHE", dir.path().c_str(), 1); }
  ~KeptCalibrations() { unsetenv("SIRL_CALIBRATION_CACHE"); }
  std::vector<std::filesystem::path> files() const {
    std::vector<std::filesystem::path> v;
    for (const auto& f : std::filesystem::directory_iterator(dir.path())) v.push_back(f.path());
    return v;
  }
};

TEST(Estimate, AKeptCalibrationGivesTheSameEstimateWithoutTimingAgain) {
  const KeptCalibrations kept;
  const Profile p = parse_profile(test::kSmallProfile, "t.toml");
  const Plan plan = make_plan(p);
  const PlanEstimate first = estimate_plan(plan, p, 2);
  ASSERT_EQ(kept.files().size(), 1u);  // one environment
  EXPECT_GT(first.calibration_wall_seconds, 0);
  const PlanEstimate again = estimate_plan(plan, p, 2);
  EXPECT_EQ(again.calibration_wall_seconds, 0);  // nothing timed
  EXPECT_EQ(again.gflops_per_s, first.gflops_per_s);
  EXPECT_EQ(again.call_seconds, first.call_seconds);
  EXPECT_EQ(again.task_seconds, first.task_seconds);
  EXPECT_EQ(again.seconds, first.seconds);
  EXPECT_EQ(again.setup_seconds, first.setup_seconds);
  EXPECT_EQ(again.data_bytes, first.data_bytes);
  // Another sample (other query counts) is another calibration.
  std::string text = test::kSmallProfile;
  text.replace(text.find("tpa_pairs = 100"), 15, "tpa_pairs = 120");
  const Profile more = parse_profile(text, "t.toml");
  estimate_plan(make_plan(more), more, 2);
  EXPECT_EQ(kept.files().size(), 2u);
}

TEST(Estimate, AKeptCalibrationThatDoesNotReadAsOneIsTimedAgain) {
  const KeptCalibrations kept;
  const Profile p = parse_profile(test::kSmallProfile, "t.toml");
  const Plan plan = make_plan(p);
  estimate_plan(plan, p, 2);
  ASSERT_EQ(kept.files().size(), 1u);
  std::ofstream(kept.files()[0], std::ios::trunc) << "sirl-calibration-1\n1\nnan\n";
  const PlanEstimate e = estimate_plan(plan, p, 2);
  EXPECT_GT(e.calibration_wall_seconds, 0);  // timed again, and stored again
  EXPECT_GT(e.gflops_per_s.at("grid/rep_sirl"), 0.01);
  EXPECT_EQ(estimate_plan(plan, p, 2).calibration_wall_seconds, 0);
}

TEST(Estimate, KeptFilesThatDoNotReadAsCalibrationsAreIgnored) {
  const KeptCalibrations kept;
  save_calibration("k", {1.0, 2.0});
  ASSERT_EQ(kept.files().size(), 1u);
  const std::filesystem::path file = kept.files()[0];
  const std::vector<std::string> bad{"",
                                     "sirl-calibration-1\n",
                                     "other-format\n1\n2\n",
                                     "sirl-calibration-1\n1\nnan\n",
                                     "sirl-calibration-1\n1\ninf\n",
                                     "sirl-calibration-1\n1\n-2\n",
                                     "sirl-calibration-1\n1x\n2\n",
                                     "sirl-calibration-1\n1e999\n"};
  for (const std::string& text : bad) {
    std::ofstream(file, std::ios::trunc) << text;
    EXPECT_FALSE(load_calibration("k").has_value()) << text;
  }
  std::ofstream(file, std::ios::trunc) << "sirl-calibration-1\n" << std::string(70000, '1') << "\n";
  EXPECT_FALSE(load_calibration("k").has_value());  // larger than any calibration
  // A FIFO where the file was is never opened (no hang) nor trusted.
  std::filesystem::remove(file);
  ASSERT_EQ(mkfifo(file.c_str(), 0600), 0);
  EXPECT_FALSE(load_calibration("k").has_value());
  save_calibration("k", {3.0});  // replaces it, as any stored calibration is replaced
  EXPECT_EQ(load_calibration("k"), std::vector<double>{3.0});
}

TEST(Estimate, KeptValuesRoundTripExactlyAndNothingIsKeptWithoutTheFolder) {
  {
    const KeptCalibrations kept;
    const std::vector<double> v{0.1, 1e-300, 123456.789, 0.0, 2.5e9};
    save_calibration("what", v);
    EXPECT_EQ(load_calibration("what"), v);
    EXPECT_FALSE(load_calibration("something else").has_value());
  }
  save_calibration("what", {1.0});  // no folder: nothing kept, nothing read
  EXPECT_FALSE(load_calibration("what").has_value());
}

}  // namespace
}  // namespace sirl
