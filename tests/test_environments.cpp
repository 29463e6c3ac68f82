// datasets/environments: the registry. A new environment is one registration: this file adds a
// toy environment and runs a smoke-sized plan on it without touching any other file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <set>

#include "datasets/environments.h"
#include "engine/hyperparams.h"
#include "experiment/profile.h"
#include "jobs/run.h"
#include "kernels/rng.h"
#include "probes/roofline.h"
#include "results/h5.h"
#include "results/results_file.h"
#include "tests/scratch_dir.h"

namespace sirl {
namespace {

// "toyline": 240 paths of 5 points in the unit square; features: mean x, mean y, length.
constexpr int kToyPoints = 5;
constexpr int64_t kToyCount = 240;

Dataset make_toy(const EnvConfig&) {
  Dataset d;
  d.env = "toyline";
  d.count = kToyCount;
  d.input_dim = 2 * kToyPoints;
  d.input_description = "5 points (x, y) in [0, 1]^2";
  d.feature_names = {"mean_x", "mean_y", "length"};
  d.feature_units = {"1", "1", "1"};
  d.object_dim = 2;
  d.object_units = "1";
  Rng rng(seed_from_key("toyline", 0));
  for (int64_t i = 0; i < d.count; ++i) {
    double sx = 0, sy = 0, len = 0, px = 0, py = 0;
    for (int k = 0; k < kToyPoints; ++k) {
      const double x = rng.uniform(), y = rng.uniform();
      d.inputs.push_back(float(x));
      d.inputs.push_back(float(y));
      sx += x, sy += y;
      if (k) len += std::hypot(x - px, y - py);
      px = x, py = y;
    }
    d.features_raw.insert(d.features_raw.end(),
                          {float(sx / kToyPoints), float(sy / kToyPoints), float(len)});
  }
  normalise_features(d);
  return d;
}

TrajectoryView draw_toy(const Dataset& d, int64_t row) {
  TrajectoryView v;
  for (int k = 0; k < kToyPoints; ++k)
    v.points.push_back({d.input(row)[2 * k], d.input(row)[2 * k + 1], 0});
  return v;
}

EnvSpec toy_spec() {
  EnvSpec e;
  e.name = "toyline";
  e.title = "Toy lines";
  e.description = "a test's toy environment";
  e.hyper = {{"phi.hidden", std::vector<int>{16, 16}}, {"tpa.hidden", std::vector<int>{8}}};
  e.make = make_toy;
  e.trajectories = [](const EnvConfig&) { return kToyCount; };
  e.input_dim = [](const EnvConfig&) { return 2 * kToyPoints; };
  e.draw = draw_toy;
  return e;
}

void register_toy_once() {
  static bool done = false;
  if (!done) register_environment(toy_spec());
  done = true;
}

TEST(Environments, RefusesATakenNameAMalformedNameAndAMissingFunction) {
  register_toy_once();
  EXPECT_THROW(register_environment(toy_spec()), std::invalid_argument);  // taken
  EnvSpec bad = toy_spec();
  bad.name = "Bad Name";
  EXPECT_THROW(register_environment(bad), std::invalid_argument);
  bad = toy_spec();
  bad.name = "toy_nodraw";
  bad.draw = nullptr;
  EXPECT_THROW(register_environment(bad), std::invalid_argument);
  EXPECT_THROW(env_spec("toy_nodraw"), std::invalid_argument);  // nothing half-registered
  bad = toy_spec();
  bad.name = "toy_sampled";
  bad.sampled = true;  // a sampled Ξ must say how its size and seed are set
  EXPECT_THROW(register_environment(bad), std::invalid_argument);
}

// A sampled environment's set_sample sets the Ξ it builds: that many trajectories, and the seed
// decides which (two seeds give different trajectories, one seed the same ones).
TEST(Environments, SetSampleSetsTheSizeAndSeedOfASampledXi) {
  const EnvSpec& e = env_spec("jaco2");
  ASSERT_TRUE(e.set_sample);
  EnvConfig a, b, c;
  e.set_sample(a, 12, 1);
  e.set_sample(b, 12, 2);
  e.set_sample(c, 12, 1);
  EXPECT_EQ(e.trajectories(a), 12);
  const Dataset da = e.make(a), db = e.make(b), dc = e.make(c);
  EXPECT_EQ(da.count, 12);
  EXPECT_NE(da.inputs, db.inputs);
  EXPECT_EQ(da.inputs, dc.inputs);
  EXPECT_FALSE(env_spec("grid").set_sample);  // enumerated
}

// GridRobot's drawing against the dataset's own features: |end angle| is the abs_angle feature
// (degrees), the 9 points are unit moves between opposite corners, in cells.
TEST(Environments, GridDrawingMatchesTheTrajectorysFeatures) {
  const EnvSpec& e = env_spec("grid");
  const Dataset d = e.make(EnvConfig{});
  for (int64_t row = 0; row < d.count; row += 37) {
    const TrajectoryView v = e.draw(d, row);
    ASSERT_EQ(v.points.size(), 9u);
    EXPECT_FLOAT_EQ(std::abs(v.end_angle_deg), d.features_raw[size_t(row) * 4 + 3]) << row;
    for (size_t k = 1; k < 9; ++k)
      EXPECT_FLOAT_EQ(std::abs(v.points[k][0] - v.points[k - 1][0]) +
                          std::abs(v.points[k][1] - v.points[k - 1][1]),
                      1.f)
          << row;
    EXPECT_FLOAT_EQ(std::abs(v.points[8][0] - v.points[0][0]), 4.f) << row;
  }
}

// JacoRobot's drawing: the arm posed at each waypoint is the base then the 7 link frames; its
// last frame is the hand the path follows, and every link keeps its length whatever the joint
// angles (rigid bodies), across waypoints and trajectories. The grid has no arm.
TEST(Environments, JacoDrawingPosesARigidArmWhoseHandIsThePath) {
  const EnvSpec& e = env_spec("jaco2");
  EnvConfig c;
  c.jaco.trajectories = 30;
  const Dataset d = e.make(c);
  std::vector<double> length;
  for (int64_t row = 0; row < d.count; ++row) {
    const TrajectoryView v = e.draw(d, row);
    ASSERT_EQ(v.links.size(), v.points.size());
    for (size_t t = 0; t < v.links.size(); ++t) {
      const auto& pose = v.links[t];
      ASSERT_EQ(pose.size(), 8u);
      EXPECT_EQ(pose[0], (std::array<float, 3>{0, 0, 0}));
      EXPECT_EQ(pose.back(), v.points[t]) << row << " " << t;
      for (size_t j = 1; j < pose.size(); ++j) {
        const double l = std::sqrt(std::pow(pose[j][0] - pose[j - 1][0], 2) +
                                   std::pow(pose[j][1] - pose[j - 1][1], 2) +
                                   std::pow(pose[j][2] - pose[j - 1][2], 2));
        if (length.size() < j) length.push_back(l);
        EXPECT_NEAR(l, length[j - 1], 1e-4) << "link " << j << " of row " << row;
      }
    }
  }
  // Not a degenerate chain: the Jaco's links add up to about a metre (some DH frames coincide).
  double reach = 0;
  for (double l : length) reach += l;
  EXPECT_GT(reach, 0.6);
  EXPECT_TRUE(env_spec("grid").draw(env_spec("grid").make(EnvConfig{}), 0).links.empty());
}

TEST(Environments, PaperHyperAppliesTheRegisteredDefaults) {
  register_toy_once();
  const Hyper toy = paper_hyper("toyline"), grid = paper_hyper("grid");
  EXPECT_EQ(toy.phi_hidden, (std::vector<int>{16, 16}));
  EXPECT_EQ(toy.tpa_hidden, (std::vector<int>{8}));
  EXPECT_EQ(toy.sirl.epochs, grid.sirl.epochs);  // everything else: the engine's defaults
  // The paper's JacoRobot differences, from the registry.
  const Hyper jaco = paper_hyper("jaco");
  EXPECT_EQ(jaco.phi_hidden, (std::vector<int>{1024, 1024}));
  EXPECT_DOUBLE_EQ(jaco.pref.adam.lr, 0.001);
  EXPECT_DOUBLE_EQ(grid.pref.adam.lr, 0.01);
  EXPECT_DOUBLE_EQ(jaco.tpa_l2, 1);
  EXPECT_DOUBLE_EQ(grid.tpa_l2, 10);
}

TEST(Environments, AToyEnvironmentRunsASmokePlanWithNoOtherCode) {
  register_toy_once();
  const std::string profile = R"(
name = "toy"
envs = ["toyline"]
seeds = [0]
[queries]
similarity = 100
preference = 100
tpa_pairs = 40
fpe_trajectories = 200
[fpe]
methods = ["sirl", "random"]
N = [50, 100]
[tpa]
methods = ["sirl", "random"]
N = [100]
M = [16]
[hyper.toyline]
"sirl.epochs" = 5
"tpa.epochs" = 5
)";
  const Profile p = parse_profile(profile, "toy.toml");
  const test::ScratchDir scratch;
  const std::string out = scratch.file("toy.h5");
  RunOptions o;
  o.out = out;
  o.threads = 2;
  o.quiet = true;
  const RunSummary s = run_profile(p, o);
  EXPECT_EQ(s.ran, s.tasks);
  EXPECT_GT(s.tasks, 0);

  const auto records = read_results_records(out);
  std::set<std::string> kinds;
  for (const auto& r : records) {
    EXPECT_EQ(r.key.rfind("toyline/s0/", 0), 0u) << r.key;
    kinds.insert(r.kind);
  }
  EXPECT_EQ(kinds, (std::set<std::string>{"rep", "fpe", "tpa", "tpa_linear"}));
  for (const auto& r : records) {
    if (r.kind == "fpe") {
      EXPECT_TRUE(std::isfinite(r.num.at("fpe")));
      EXPECT_GE(r.num.at("fpe"), 0);
    }
    if (r.kind == "tpa") {
      // The record's summary numbers are the means of its per-reward arrays.
      const auto mean = [](const std::vector<float>& v) {
        double s = 0;
        for (float x : v) s += x;
        return s / double(v.size());
      };
      EXPECT_NEAR(r.num.at("tpa"), mean(r.arrays.at("accuracy").data), 1e-6) << r.key;
      EXPECT_NEAR(r.num.at("tpa_train"), mean(r.arrays.at("train_accuracy").data), 1e-6) << r.key;
      EXPECT_NE(r.num.at("tpa"), r.num.at("tpa_train")) << r.key;
    }
  }
  const H5File f = H5File::open_read(out);
  EXPECT_EQ(f.attr_string("/datasets/toyline", "title"), "Toy lines");
}

// precision = "bf16": every record of a task whose networks ran in bf16 says so (rep, tpa), FPE's
// linear probe does not; the results file carries a bf16 roof exactly where this CPU has a bf16
// unit (probes/roofline.h), and an fp32 run never does.
TEST(Environments, ABf16RunMarksItsNetworkTasksAndRecordsItsRoof) {
  register_toy_once();
  const std::string profile = R"(
name = "toy-bf16"
precision = "bf16"
envs = ["toyline"]
seeds = [0]
[queries]
similarity = 60
preference = 60
tpa_pairs = 30
fpe_trajectories = 100
[fpe]
methods = ["sirl"]
N = [50]
[tpa]
methods = ["sirl"]
N = [50]
M = [8]
[hyper.toyline]
"sirl.epochs" = 2
"tpa.epochs" = 2
)";
  const test::ScratchDir scratch;
  for (const bool bf16 : {true, false}) {
    std::string text = profile;
    if (!bf16) text.replace(text.find("\"bf16\""), 6, "\"fp32\"");
    RunOptions o;
    o.out = scratch.file(bf16 ? "bf16.h5" : "fp32.h5");
    o.threads = 1;
    o.quiet = true;
    run_profile(parse_profile(text, "toy.toml"), o);
    std::set<std::string> marked;
    for (const auto& r : read_results_records(o.out)) {
      const auto it = r.num.find("bf16_products");
      if (it != r.num.end() && it->second != 0) marked.insert(r.kind);
    }
    const std::set<std::string> want =
        bf16 ? std::set<std::string>{"rep", "tpa"} : std::set<std::string>{};
    EXPECT_EQ(marked, want);
    const RunInfo info = read_run_info(o.out);
    EXPECT_EQ(info.roof_bf16_gflops, bf16 ? bf16_roof_gflops_per_core() : 0.0);
    EXPECT_GT(info.roof_fp32_gflops, 0);
  }
}

}  // namespace
}  // namespace sirl
