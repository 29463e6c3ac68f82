// Hyper-parameter axes: a [hyper.<env>] key given as a list runs the environment's grid at every
// value (every combination of several axes), the first values being the base point whose tasks
// keep the keys a profile without the axes gives them; a task the point does not change is the
// base point's task, shared.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/simulation_tasks.h"
#include "experiment/task_digest.h"
#include "tests/profile_error.h"
#include "tests/small_profile.h"

namespace sirl {
namespace {

// The small profile with lines added to [hyper.grid], replacing its own lines of the same keys
// (its "sirl.epochs" and "tpa.hidden"): TOML allows a key once per table.
std::string small_with_hyper(const std::string& lines) {
  std::string text = test::kSmallProfile;
  for (const char* own : {"\"sirl.epochs\" = 7\n", "\"tpa.hidden\" = [32, 16]\n"}) {
    const std::string key = std::string(own).substr(0, std::string(own).find(" ="));
    if (lines.find(key) != std::string::npos) text.erase(text.find(own), std::string(own).size());
  }
  const std::string at = "[hyper.grid]\n";
  return text.insert(text.find(at) + at.size(), lines + "\n");
}

std::set<std::string> axis_plan_keys(const Profile& p) {
  std::set<std::string> k;
  for (const Task& t : make_plan(p).tasks) k.insert(t.key);
  return k;
}

TEST(HyperAxes, AListIsAnAxisWhoseFirstValueIsTheBase) {
  const Profile p = parse_profile(small_with_hyper("\"tpa.lr\" = [0.002, 0.001, 0.0005]"));
  ASSERT_EQ(p.hyper_points.at("grid").size(), 3u);
  EXPECT_EQ(p.hyper_points.at("grid")[0].tag, "tpa.lr=0.002");
  EXPECT_EQ(p.hyper_points.at("grid")[2].tag, "tpa.lr=0.00050000000000000001");
  EXPECT_EQ(p.hyper.at("grid").tpa.adam.lr, 0.002);  // the base point
  EXPECT_EQ(hyper_at(p, "grid", "tpa.lr=0.001").tpa.adam.lr, 0.001);
  EXPECT_EQ(hyper_at(p, "grid", "").tpa.adam.lr, 0.002);
  EXPECT_EQ(hyper_point_tags(p, "grid"),
            (std::vector<std::string>{"", "tpa.lr=0.001", "tpa.lr=0.00050000000000000001"}));
  EXPECT_THROW(hyper_at(p, "grid", "tpa.lr=7"), std::invalid_argument);
  EXPECT_EQ(hyper_points_text(p),
            "grid\ttpa.lr=0.002\ttpa.lr=0.001\ttpa.lr=0.00050000000000000001\n");
}

TEST(HyperAxes, TwoAxesGiveEveryCombinationAndWidthsTakeListsOfLists) {
  const Profile p = parse_profile(
      small_with_hyper("\"tpa.hidden\" = [[32, 16], [64]]\n\"sirl.margin\" = [1.0, 0.5]"));
  std::vector<std::string> tags;
  for (const HyperPoint& hp : p.hyper_points.at("grid")) tags.push_back(hp.tag);
  // Axes in the order of their keys' names, each axis's values in the order given.
  EXPECT_EQ(tags, (std::vector<std::string>{
                      "sirl.margin=1;tpa.hidden=32,16", "sirl.margin=1;tpa.hidden=64",
                      "sirl.margin=0.5;tpa.hidden=32,16", "sirl.margin=0.5;tpa.hidden=64"}));
  const Hyper& last = hyper_at(p, "grid", "sirl.margin=0.5;tpa.hidden=64");
  EXPECT_EQ(last.tpa_hidden, (std::vector<int>{64}));
  EXPECT_EQ(last.triplet_margin, 0.5);
  EXPECT_EQ(parse_profile(small_with_hyper("\"phi.hidden\" = [64, 64]")).hyper_points.count("grid"),
            0u)
      << "a plain width list is a value, not an axis";
}

TEST(HyperAxes, BadAxesAreRefusedWithTheirLine) {
  for (const auto& [line, want] : std::vector<std::pair<std::string, std::string>>{
           {"\"sirl.epochs\" = []", "needs at least one value"},
           {"\"sirl.epochs\" = [30, 30]", "listed twice"},
           {"\"sirl.margin\" = [1, 1.0]", "listed twice"},  // one text, one point name
           {"\"sirl.epochs\" = [30, 30.5]", "sirl.epochs must be"},
           {"\"sirl.epochs\" = [30, -1]", "sirl.epochs must be >= 1"},
           {"\"sirl.epochs\" = [0, 30]", "sirl.epochs must be >= 1"},
           {"\"tpa.stop\" = [\"fixed\", \"never\"]", "tpa.stop"}}) {
    const std::string err = test::profile_error_of(small_with_hyper(line));
    EXPECT_NE(err.find(want), std::string::npos) << line << " → " << err;
    EXPECT_NE(err.find("bad.toml:"), std::string::npos) << err;
  }
}

// A value list long enough to be a paste error, and axes whose product is, are refused before
// any point is built: each costs a line, not gigabytes or minutes.
TEST(HyperAxes, LongAxesAndLargeProductsAreRefusedBeforeExpansion) {
  std::string many = "\"sirl.margin\" = [";
  for (int i = 0; i < 20000; ++i) many += (i ? ", " : "") + std::to_string(1.0 + i * 1e-3);
  std::string err = test::profile_error_of(small_with_hyper(many + "]"));
  EXPECT_NE(err.find("an axis of 20000 values"), std::string::npos) << err;
  EXPECT_NE(err.find("bad.toml:"), std::string::npos) << err;

  const auto axis = [](const std::string& key, int n, int first) {
    std::string s = "\"" + key + "\" = [";
    for (int i = 0; i < n; ++i) s += (i ? ", " : "") + std::to_string(first + i);
    return s + "]\n";
  };
  // 64 × 64 × 64 = 262,144 points: refused at the second axis (4,096 > 256).
  err = test::profile_error_of(small_with_hyper(
      axis("sirl.epochs", 64, 1) + axis("tpa.epochs", 64, 1) + axis("vae.epochs", 64, 1)));
  EXPECT_NE(err.find("already make 4096 combinations"), std::string::npos) << err;
  // 16 × 16 = 256 is the most a profile may ask for.
  const Profile p =
      parse_profile(small_with_hyper(axis("sirl.epochs", 16, 1) + axis("tpa.epochs", 16, 1)));
  EXPECT_EQ(p.hyper_points.at("grid").size(), 256u);
}

// A profile within every per-list cap can still multiply into millions of tasks (a stored
// profile text that `merge --partial` plans is anyone's): the plan stops at kMaxPlanTasks.
TEST(HyperAxes, APlanOfMoreThanTheCapIsRefusedAsItGrows) {
  std::string text = small_with_hyper("\"sirl.margin\" = [" + [] {
    std::string v;
    for (int i = 0; i < 200; ++i) v += (i ? ", " : "") + std::to_string(1 + i);
    return v;
  }() + "]");
  std::string seeds = "seeds = [";
  for (int i = 0; i < 1000; ++i) seeds += (i ? ", " : "") + std::to_string(i);
  text.replace(text.find("seeds = [0, 1, 2]"), std::string("seeds = [0, 1, 2]").size(),
               seeds + "]");
  const Profile p = parse_profile(text);
  try {
    make_plan(p);
    ADD_FAILURE() << "a plan of millions of tasks was built";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("more than 50000 tasks"), std::string::npos) << e.what();
  }
}

TEST(HyperAxes, OnlyTheTasksAPointChangesGetAPointAndTheBaseKeepsItsKeysAndDigests) {
  const Profile plain = parse_profile(test::kSmallProfile);
  const Profile axis = parse_profile(small_with_hyper("\"tpa.epochs\" = [500, 40]"));
  const std::set<std::string> base = axis_plan_keys(plain), all = axis_plan_keys(axis);
  EXPECT_TRUE(std::includes(all.begin(), all.end(), base.begin(), base.end()));
  int tpa_cells = 0;
  for (const auto& k : base)  // the paper's heads: linear cells read no tpa.epochs
    tpa_cells += k.find("/tpa/") != std::string::npos && !k.ends_with("/linear");
  std::vector<std::string> added;
  std::set_difference(all.begin(), all.end(), base.begin(), base.end(), std::back_inserter(added));
  EXPECT_EQ(int(added.size()), tpa_cells) << "a TPA axis adds exactly one copy of every TPA cell";
  for (const auto& k : added) {
    EXPECT_NE(k.find("/tpa.epochs=40/"), std::string::npos) << k;
    EXPECT_NE(k.find("/tpa/"), std::string::npos) << k;
  }
  // The base point's digests are a plain profile's: its cached results are reused.
  const Plan pp = make_plan(plain), pa = make_plan(axis);
  const auto dp = task_digests(pp), da = task_digests(pa);
  for (size_t i = 0; i < pp.tasks.size(); ++i)
    EXPECT_EQ(dp[i], da[size_t(pa.index.at(pp.tasks[i].key))]) << pp.tasks[i].key;
  // A cell at the point reads the base point's φ.
  const Task& cell =
      pa.tasks[size_t(pa.index.at("grid/s0/tpa.epochs=40/sirl/N100/tpa/M10/frozen"))];
  EXPECT_EQ(cell.input(rep_kind()), "grid/s0/sirl/N100/rep");
  EXPECT_EQ(cell.hyper, "tpa.epochs=40");
}

TEST(HyperAxes, APointOfAnInputCarriesToItsReaders) {
  const Profile p = parse_profile(small_with_hyper("\"vae.epochs\" = [3, 4]"));
  const Plan plan = make_plan(p);
  const auto has = [&](const std::string& k) { return plan.index.count(k) > 0; };
  EXPECT_TRUE(has("grid/s0/vae.epochs=4/vae"));
  EXPECT_TRUE(has("grid/s0/vae.epochs=4/sirl+vae/N100/rep"));  // reads the VAE
  EXPECT_TRUE(has("grid/s0/vae.epochs=4/sirl+vae/N100/fpe"));  // reads that φ
  EXPECT_FALSE(has("grid/s0/vae.epochs=4/sirl/N100/rep"));     // no VAE in it
  EXPECT_FALSE(has("grid/s0/vae.epochs=4/random/fpe"));
  const Task& rep = plan.tasks[size_t(plan.index.at("grid/s0/vae.epochs=4/sirl+vae/N100/rep"))];
  EXPECT_EQ(rep.input(vae_kind()), "grid/s0/vae.epochs=4/vae");
}

}  // namespace
}  // namespace sirl
