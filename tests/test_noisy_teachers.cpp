// Noisy teachers as an axis of the experiment: the answer statistics of the perfect and the
// β = 0 teacher, the paired design (every teacher asked the same queries), TPA's held-out pairs
// labelled by the truth, the attend mask, and the [teacher] lists → [robustness] cells.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <string>

#include "datasets/grid_robot.h"
#include "datasets/query_bundle.h"
#include "datasets/simulated_human.h"
#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/simulation_tasks.h"
#include "tests/profile_error.h"

namespace sirl {
namespace {

QueryBundleConfig small_config() {
  QueryBundleConfig c;
  c.similarity = 1200;
  c.preference = 600;
  c.tpa_pairs = 40;
  c.fpe_trajectories = 100;
  return c;
}

// β = 0 answers at random whatever the options: each of a triplet's three pairs a third of the
// time, each side of a pair half the time — even where the truth is clear.
TEST(NoisyTeacher, BetaZeroAnswersUniformlyAtRandom) {
  Teacher coin;
  coin.beta = 0;
  validate(coin, 3);  // β = 0 is a valid teacher (β < 0 is not)
  Teacher bad;
  bad.beta = -1;
  EXPECT_THROW(validate(bad, 3), std::invalid_argument);
  const float a[3] = {0, 0, 0}, b[3] = {0.01f, 0, 0}, far[3] = {5, 5, 5};
  Rng rng(11);
  std::array<int, 3> odd{};  // how often each position was called the odd one out
  const int n = 9000;
  for (int i = 0; i < n; ++i) ++odd[size_t(answer_similarity(coin, a, b, far, 3, rng)->neg)];
  // Binomial(9000, 1/3): σ ≈ 45, so ±200 is > 4 σ.
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(odd[size_t(k)], n / 3.0, 200) << k;
  const float w[3] = {1, 0, 0};
  int a_preferred = 0;
  for (int i = 0; i < n; ++i) a_preferred += *answer_preference(coin, w, far, a, 3, rng) == 1.f;
  EXPECT_NEAR(a_preferred, n / 2.0, 200);
  // The perfect teacher: always the closest pair (b, a | far) and the higher reward.
  const Teacher perfect;
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(answer_similarity(perfect, a, b, far, 3, rng)->neg, 2);
    EXPECT_EQ(*answer_preference(perfect, w, far, a, 3, rng), 1.f);
  }
}

// Every teacher of one seed is asked the same queries (its noise draws from streams of its
// own), so the robustness axis is a paired comparison; only the answers differ, and TPA's
// held-out pairs carry the true labels for every teacher.
TEST(NoisyTeacher, EveryTeacherIsAskedTheSameQueriesAndTestedOnTheTruth) {
  const Dataset d = make_grid_dataset();
  const QueryBundleConfig pc = small_config();
  QueryBundleConfig nc = pc;
  nc.teacher.beta = 1;
  const QueryBundle perfect = make_query_bundle(d, pc, 5), noisy = make_query_bundle(d, nc, 5);
  ASSERT_EQ(perfect.similarity.count, noisy.similarity.count);
  int reordered = 0;
  for (int64_t i = 0; i < perfect.similarity.count; ++i) {
    std::array<int32_t, 3> p, q;
    std::copy_n(perfect.similarity.idx.begin() + 3 * i, 3, p.begin());
    std::copy_n(noisy.similarity.idx.begin() + 3 * i, 3, q.begin());
    reordered += p != q;
    std::sort(p.begin(), p.end());
    std::sort(q.begin(), q.end());
    ASSERT_EQ(p, q) << "triplet " << i << " is not the same three trajectories";
  }
  EXPECT_GT(reordered, 0) << "β = 1 never answered differently";
  EXPECT_EQ(perfect.singlepref.pairs, noisy.singlepref.pairs);
  EXPECT_EQ(perfect.multipref50.pairs, noisy.multipref50.pairs);
  EXPECT_NE(perfect.multipref50.label, noisy.multipref50.label);
  for (size_t r = 0; r < perfect.tpa.size(); ++r) {
    const TpaSet &a = perfect.tpa[r], &b = noisy.tpa[r];
    ASSERT_EQ(a.pairs.pairs, b.pairs.pairs);
    ASSERT_EQ(a.train, b.train);
    for (int64_t i = a.train; i < a.pairs.count; ++i)
      ASSERT_EQ(a.pairs.label[size_t(i)], b.pairs.label[size_t(i)])
          << "reward " << r << " pair " << i;
  }
  EXPECT_EQ(perfect.fpe.train, noisy.fpe.train);
  // The perfect teacher's bundle opened no answer streams: it is what it always was.
  for (const auto& s : perfect.streams) EXPECT_EQ(s.rfind("answers/", 0), std::string::npos) << s;
}

// AnswerError: 0 for the perfect teacher; for β = 0, 2/3 of triplets name another pair than the
// closest and half the preference labels are wrong; a mistake rate ε flips that share of
// similarity answers (each flip lands on a wrong pair).
TEST(NoisyTeacher, AnswerErrorMatchesTheNoiseModel) {
  const Dataset d = make_grid_dataset();
  QueryBundleConfig c = small_config();
  const QueryBundle perfect = make_query_bundle(d, c, 2);
  EXPECT_EQ(perfect.answer_error.similarity, 0.0);
  EXPECT_EQ(perfect.answer_error.preference, 0.0);
  c.teacher.beta = 0;
  const QueryBundle coin = make_query_bundle(d, c, 2);
  // n = 1200 triplets: σ ≈ 0.014; ≈ 2600 pairs: σ ≈ 0.01. Grid features tie sometimes (a tie
  // counts as agreement), which lowers both a little.
  EXPECT_NEAR(coin.answer_error.similarity, 2.0 / 3, 0.07);
  EXPECT_NEAR(coin.answer_error.preference, 0.5, 0.06);
  c.teacher.beta = std::numeric_limits<double>::infinity();
  c.teacher.mistake = 0.2;
  const QueryBundle slips = make_query_bundle(d, c, 2);
  EXPECT_NEAR(slips.answer_error.similarity, 0.2, 0.05);
  EXPECT_NEAR(slips.answer_error.preference, 0.2, 0.04);
}

// attend = 0.5: the teacher perceives round(0.5·F) features, drawn once per seed, and answers
// by those alone — every stored triplet's pair is the closest under the masked distance.
TEST(NoisyTeacher, AttendDrawsAMaskAndTheTeacherAnswersByIt) {
  const Dataset d = make_grid_dataset();
  QueryBundleConfig c = small_config();
  c.attend = 0.5;
  const QueryBundle b = make_query_bundle(d, c, 4);
  const auto& mask = b.config.teacher.mask;
  ASSERT_EQ(int(mask.size()), d.feature_count());
  EXPECT_EQ(std::count(mask.begin(), mask.end(), 1), std::lround(0.5 * d.feature_count()));
  EXPECT_EQ(make_query_bundle(d, c, 4).config.teacher.mask, mask) << "same seed, another mask";
  auto dist = [&](int32_t i, int32_t j) {
    double s = 0;
    for (int f = 0; f < d.feature_count(); ++f)
      if (mask[size_t(f)]) s += std::pow(d.feature(i)[f] - d.feature(j)[f], 2);
    return s;
  };
  for (int64_t i = 0; i < b.similarity.count; ++i) {
    const int32_t* t = b.similarity.idx.data() + 3 * i;
    ASSERT_LE(dist(t[0], t[1]), dist(t[0], t[2]) + 1e-9);
    ASSERT_LE(dist(t[0], t[1]), dist(t[1], t[2]) + 1e-9);
  }
  EXPECT_GT(b.answer_error.similarity, 0.05) << "seeing half the features changed nothing";
  c.attend = 0;
  EXPECT_THROW(make_query_bundle(d, c, 4), std::invalid_argument);
}

constexpr const char* kRobust = R"(
name = "r"
envs = ["grid"]
seeds = [0, 1]
[queries]
similarity = 200
preference = 200
tpa_pairs = 100
[teacher]
beta = ["inf", 10, 0]
mistake = [0.2]
[fpe]
methods = ["sirl"]
N = [100]
[robustness]
methods = ["sirl", "multipref10", "random"]
N = [200]
M = [40]
)";

TEST(NoisyTeacher, TeacherListsBecomeAxisPointsBesideThePerfectMainTeacher) {
  const Profile p = parse_profile(kRobust, "r.toml");
  EXPECT_TRUE(p.queries.teacher.perfect()) << "a list keeps the main teacher perfect";
  ASSERT_EQ(p.robustness.teachers.size(), 3u);  // "inf" is the main teacher itself
  EXPECT_EQ(p.robustness.teachers[0].tag, "beta=10");
  EXPECT_EQ(p.robustness.teachers[1].tag, "beta=0");
  EXPECT_EQ(p.robustness.teachers[1].queries.teacher.beta, 0);
  EXPECT_EQ(p.robustness.teachers[2].tag, "mistake=0.2");
  EXPECT_EQ(p.robustness.teachers[2].queries.teacher.mistake, 0.2);
  EXPECT_TRUE(std::isinf(p.robustness.teachers[2].queries.teacher.beta));
  EXPECT_EQ(&queries_for(p, ""), &p.queries);
  EXPECT_EQ(queries_for(p, "beta=0").teacher.beta, 0);
  EXPECT_THROW(queries_for(p, "beta=3"), std::invalid_argument);

  const Plan plan = make_plan(p);
  // Per seed and teacher: FPE of SIRL and MultiPref-10 (Random's φ learns from no answers);
  // TPA of all three (SIRL frozen, the others unfrozen: "best").
  EXPECT_EQ(plan.count(robust_fpe_kind()), 2 * 3 * 2);
  EXPECT_EQ(plan.count(robust_tpa_kind()), 2 * 3 * 3);
  ASSERT_TRUE(plan.index.count("grid/s1/beta=0/sirl/N200/rep"));
  ASSERT_TRUE(plan.index.count("grid/s1/beta=0/sirl/N200/tpa/M40/frozen"));
  ASSERT_TRUE(plan.index.count("grid/s1/beta=0/random/tpa/M40/unfrozen"));
  EXPECT_FALSE(plan.index.count("grid/s1/beta=0/random/rep")) << "Random's φ is one for all";
  const Task& rt = plan.tasks[size_t(plan.index.at("grid/s1/beta=0/random/tpa/M40/unfrozen"))];
  ASSERT_EQ(rt.deps.size(), 1u);
  EXPECT_EQ(plan.tasks[size_t(rt.deps[0])].key, "grid/s1/random/rep");
  // The main teacher's cells of the same sizes are the reference points.
  EXPECT_TRUE(plan.index.count("grid/s0/sirl/N200/fpe"));
  EXPECT_TRUE(plan.index.count("grid/s0/multipref10/N200/tpa/M40/unfrozen"));
  EXPECT_TRUE(plan.index.count("grid/s0/sirl/N100/fpe"));  // the main grid, untouched
}

TEST(NoisyTeacher, InconsistentRobustnessProfilesAreRejected) {
  const std::string base =
      "name = \"x\"\nenvs = [\"grid\"]\nseeds = [0]\n[fpe]\nmethods = [\"sirl\"]\nN = [100]\n";
  const std::string cells = "[robustness]\nmethods = [\"sirl\"]\nN = [100]\nM = [10]\n";
  auto has = [](const std::string& m, const std::string& what) {
    return m.find(what) != std::string::npos;
  };
  std::string m = test::profile_error_of(base + "[teacher]\nbeta = [1, 0]\n");
  EXPECT_TRUE(has(m, "no [robustness] table")) << m;
  m = test::profile_error_of(base + cells);
  EXPECT_TRUE(has(m, "[robustness] needs noisy teachers")) << m;
  m = test::profile_error_of(base + "[teacher]\nbeta = [1, 1]\n" + cells);
  EXPECT_TRUE(has(m, "listed twice")) << m;
  m = test::profile_error_of(base + "[teacher]\nmistake = [0.1, 1.5]\n" + cells);
  EXPECT_TRUE(has(m, "bad.toml:8: mistake = 1.5 is outside [0, 1]")) << m;
  m = test::profile_error_of(base + "[teacher]\nattend = [0]\n" + cells);
  EXPECT_TRUE(has(m, "attend = 0 is outside")) << m;
  m = test::profile_error_of(
      base +
      "[teacher]\nbeta = [1]\n[robustness]\nmethods = [\"sirl\"]\nN = [100]\n"
      "M = [1000]\n");
  EXPECT_TRUE(has(m, "M = 1000 exceeds")) << m;
  m = test::profile_error_of(base + "[teacher]\nbeta = [1]\n" + cells + "seeds = [1]\n");
  EXPECT_TRUE(has(m, "unknown key 'seeds' in [robustness]")) << m;
}

}  // namespace
}  // namespace sirl

namespace sirl {
namespace {

constexpr const char* kActive = R"(
name = "a"
envs = ["grid", "jaco"]
seeds = [0]
[queries]
similarity = 300
preference = 300
tpa_pairs = 100
[fpe]
methods = ["sirl", "sirl@vote", "sirl+vae@infogain"]
N = [100, 300]
[active]
members = 4
batch = 50
pool = 500
[active.jaco]
members = 3
round_epochs = 5
)";

TEST(ActiveVariants, ParseNameAndPlanTheirQueryTasks) {
  EXPECT_EQ(parse_variant("sirl+vae@infogain").name(), "sirl+vae@infogain");
  EXPECT_EQ(parse_variant("sirl@vote").selection, Selection::vote);
  EXPECT_EQ(parse_variant("sirl").selection, Selection::uniform);
  EXPECT_THROW(parse_variant("multipref10@vote"), std::invalid_argument);
  EXPECT_THROW(parse_variant("sirl@bald"), std::invalid_argument);

  const Profile p = parse_profile(kActive, "a.toml");
  EXPECT_EQ(p.active.at("grid").members, 4);
  EXPECT_EQ(p.active.at("grid").round_epochs, 50);  // the default
  EXPECT_EQ(p.active.at("jaco").members, 3);        // [active.jaco] over [active]
  EXPECT_EQ(p.active.at("jaco").batch, 50);         // [active]'s, not overridden
  EXPECT_EQ(p.active.at("jaco").round_epochs, 5);

  const Plan plan = make_plan(p);
  EXPECT_EQ(plan.count(active_kind()), 2 * 2);  // per env: one query set per rule
  // Both N of an active variant read the one query set (nested, like the uniform set).
  for (const char* rep : {"grid/s0/sirl@vote/N100/rep", "grid/s0/sirl@vote/N300/rep"}) {
    const Task& t = plan.tasks[size_t(plan.index.at(rep))];
    ASSERT_EQ(t.deps.size(), 1u) << rep;
    EXPECT_EQ(plan.tasks[size_t(t.deps[0])].key, "grid/s0/active/vote");
  }
  const Task& v = plan.tasks[size_t(plan.index.at("jaco/s0/sirl+vae@infogain/N300/rep"))];
  ASSERT_EQ(v.deps.size(), 2u);  // the VAE it starts from and the triplets it learns from
  EXPECT_EQ(plan.tasks[size_t(v.deps[0])].key, "jaco/s0/vae");
  EXPECT_EQ(plan.tasks[size_t(v.deps[1])].key, "jaco/s0/active/infogain");
  EXPECT_GT(plan.tasks[size_t(plan.index.at("jaco/s0/active/infogain"))].flops,
            plan.tasks[size_t(plan.index.at("grid/s0/active/infogain"))].flops);

  const std::string base =
      "name = \"x\"\nenvs = [\"grid\"]\nseeds = [0]\n[fpe]\nmethods = "
      "[\"sirl@vote\"]\nN = [100]\n";
  std::string m = test::profile_error_of(base + "[active]\npool = 10\nbatch = 20\n");
  EXPECT_NE(m.find("pool = 10 is below batch = 20"), std::string::npos) << m;
  m = test::profile_error_of(base + "[active]\nmembers = 1\n");
  EXPECT_NE(m.find("members = 1 is outside [2, 64]"), std::string::npos) << m;
  m = test::profile_error_of(base + "[active.jaco]\nmembers = 3\n");
  EXPECT_NE(m.find("unknown key 'jaco' in [active]"), std::string::npos) << m;
}

}  // namespace
}  // namespace sirl
