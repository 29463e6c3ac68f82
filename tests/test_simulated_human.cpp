#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "datasets/grid_robot.h"
#include "datasets/queries.h"
#include "datasets/query_bundle.h"

namespace sirl {
namespace {

TEST(SimilarityOracle, PicksTheClosestPairOnHandMadeTriplets) {
  Teacher t;
  Rng rng(1);
  const float a[2] = {0, 0}, b[2] = {1, 1}, c[2] = {0.1f, 0};
  // a and c are closest → positives (0, 2), negative 1.
  auto r = answer_similarity(t, a, b, c, 2, rng);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->p1, 0);
  EXPECT_EQ(r->p2, 2);
  EXPECT_EQ(r->neg, 1);
  // b and c closest.
  const float a2[2] = {5, 5};
  r = answer_similarity(t, a2, b, c, 2, rng);
  EXPECT_EQ(r->p1, 1);
  EXPECT_EQ(r->p2, 2);
  EXPECT_EQ(r->neg, 0);
}

TEST(SimilarityOracle, FeatureMaskIsHonoured) {
  // In feature 0, (a, b) are close; in feature 1, (a, c) are. A teacher who perceives only
  // feature 1 must answer (a, c).
  const float a[2] = {0, 0}, b[2] = {0.05f, 1}, c[2] = {1, 0.05f};
  Rng rng(2);
  Teacher all, only1;
  only1.mask = {0, 1};
  Teacher only0;
  only0.mask = {1, 0};
  EXPECT_EQ(answer_similarity(only1, a, b, c, 2, rng)->neg, 1);
  EXPECT_EQ(answer_similarity(only0, a, b, c, 2, rng)->neg, 2);
  // Preferences: w = (1, −1) under mask {0,1} sees only −f1: A = a (0) vs B = b (−1) → A wins.
  const float w[2] = {1, -1};
  EXPECT_EQ(*answer_preference(only1, w, a, b, 2, rng), 1.f);
  // Unmasked: R(a) = 0, R(b) = 0.05 − 1 = −0.95 → A wins too; R(c) = 0.95 → C beats A.
  EXPECT_EQ(*answer_preference(all, w, a, c, 2, rng), 0.f);
  Teacher bad;
  bad.mask = {0, 0};
  EXPECT_THROW(validate(bad, 2), std::invalid_argument);
  bad.mask = {1};
  EXPECT_THROW(validate(bad, 2), std::invalid_argument);
}

TEST(PreferenceOracle, SkipEqualAndMistake) {
  const float w[1] = {1}, lo[1] = {0.f}, mid[1] = {0.05f}, hi[1] = {1.f};
  Rng rng(3);
  Teacher t;
  t.skip = 0.01;
  t.equal = 0.1;
  EXPECT_FALSE(answer_preference(t, w, lo, lo, 1, rng));       // |ΔR| = 0 < skip
  EXPECT_EQ(*answer_preference(t, w, lo, mid, 1, rng), 0.5f);  // 0.05 < equal
  EXPECT_EQ(*answer_preference(t, w, hi, lo, 1, rng), 1.f);
  Teacher always_wrong;
  always_wrong.mistake = 1.0;
  EXPECT_EQ(*answer_preference(always_wrong, w, hi, lo, 1, rng), 0.f);
}

// Agreement of a Boltzmann teacher with the perfect oracle on random GridRobot queries.
double agreement(const Dataset& d, double beta, bool similarity) {
  Rng rng(seed_from_key("agreement"));
  Teacher perfect, noisy;
  noisy.beta = beta;
  const auto rewards = make_reward_sets(4, 7);
  int agree = 0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const int a = int(rng.uniform_int(d.count)), b = int(rng.uniform_int(d.count)),
              c = int(rng.uniform_int(d.count));
    if (similarity) {
      const auto p = answer_similarity(perfect, d.feature(a), d.feature(b), d.feature(c), 4, rng);
      const auto q = answer_similarity(noisy, d.feature(a), d.feature(b), d.feature(c), 4, rng);
      agree += p->neg == q->neg;
    } else {
      const float* w = rewards.test.weights.data() + 4 * (i % 20);
      agree += *answer_preference(perfect, w, d.feature(a), d.feature(b), 4, rng) ==
               *answer_preference(noisy, w, d.feature(a), d.feature(b), 4, rng);
    }
  }
  return double(agree) / n;
}

TEST(BoltzmannTeacher, AgreementFallsAsBetaFalls) {
  const Dataset d = make_grid_dataset();
  for (bool sim : {true, false}) {
    const double a100 = agreement(d, 100, sim), a10 = agreement(d, 10, sim),
                 a1 = agreement(d, 1, sim), a001 = agreement(d, 0.01, sim);
    // n = 4000 ⇒ standard error ≤ 0.008: gaps of 0.03 are > 3.5 σ.
    EXPECT_GT(a100, a10 + 0.03) << (sim ? "similarity" : "preference");
    EXPECT_GT(a10, a1 + 0.03) << (sim ? "similarity" : "preference");
    EXPECT_GT(a100, 0.85);
    // β → 0 is a coin among the options: 1/3 for triplets, 1/2 for pairs (±0.03).
    EXPECT_NEAR(a001, sim ? 1.0 / 3 : 0.5, 0.03);
  }
}

// Every query shows distinct trajectories: a triplet three, a preference pair two (a query
// comparing a trajectory with itself carries no information and biases the answer).
TEST(Queries, EveryQueryShowsDistinctTrajectories) {
  const Dataset d = make_grid_dataset();
  QueryBundleConfig c;
  c.similarity = 3000;  // with 1960 rows, repeats would certainly appear if allowed
  c.preference = 3000;
  c.tpa_pairs = 50;
  const QueryBundle b = make_query_bundle(d, c, 9);
  for (int64_t i = 0; i < b.similarity.count; ++i) {
    const int32_t* q = b.similarity.idx.data() + 3 * i;
    ASSERT_TRUE(q[0] != q[1] && q[0] != q[2] && q[1] != q[2]) << "triplet " << i;
  }
  for (const PreferenceSet* p : {&b.singlepref, &b.multipref10, &b.multipref50})
    for (int64_t i = 0; i < p->count; ++i) ASSERT_NE(p->pairs[2 * i], p->pairs[2 * i + 1]) << i;
}

TEST(Rewards, UnitNormDisjointAndSeeded) {
  const auto r = make_reward_sets(4, 11);
  EXPECT_EQ(r.test.count, 20);
  EXPECT_EQ(r.multipref10.count, 10);
  EXPECT_EQ(r.multipref50.count, 50);
  for (const RewardSet* s : {&r.test, &r.multipref10, &r.multipref50, &r.singlepref})
    for (int i = 0; i < s->count; ++i) {
      double n = 0;
      for (int k = 0; k < 4; ++k) n += double(s->weights[4 * i + k]) * s->weights[4 * i + k];
      EXPECT_NEAR(n, 1.0, 1e-6);
    }
  EXPECT_FLOAT_EQ(r.singlepref.weights[0], 0.5f);
  EXPECT_EQ(make_reward_sets(4, 11).test.weights, r.test.weights);
  EXPECT_NE(make_reward_sets(4, 12).test.weights, r.test.weights);
  EXPECT_NE(r.test.weights[0], r.multipref10.weights[0]);
}

// The bundle lists every random stream it drew from (reward sets and query sets). One stream
// feeding two things correlates them (a MultiPref human's weights and its first queries were
// once drawn from one stream), so every name must be distinct, and each set must have one.
TEST(QueryBundle, EveryRandomStreamHasItsOwnName) {
  const Dataset d = make_grid_dataset();
  QueryBundleConfig c;
  c.similarity = 50;
  c.preference = 100;
  c.tpa_pairs = 20;
  c.fpe_trajectories = 100;
  const QueryBundle b = make_query_bundle(d, c, 3);
  const std::set<std::string> names(b.streams.begin(), b.streams.end());
  EXPECT_EQ(names.size(), b.streams.size()) << "a stream name is used twice";
  // 3 random reward sets, the similarity set, 3 preference sets, 20 TPA sets, the FPE split.
  EXPECT_EQ(b.streams.size(), size_t(3 + 1 + 3 + b.rewards.test.count + 1));
  for (const char* set : {"test", "multipref10", "multipref50"})
    EXPECT_TRUE(names.count(std::string("rewards/") + set)) << set;
  for (const char* set : {"similarity", "singlepref", "multipref10", "multipref50", "fpe"})
    EXPECT_TRUE(names.count(std::string("queries/") + set)) << set;
  // And the sets really are independent draws: the MultiPref-10 humans' weights are not the
  // normals of the stream that picks their queries.
  Rng q = Rng(seed_from_key("queries/multipref10", 3));
  const RewardSet from_query_stream = make_random_rewards("multipref10", 10, 4, q);
  EXPECT_NE(from_query_stream.weights, b.rewards.multipref10.weights);
}

TEST(StreamSet, RefusesToOpenANameTwice) {
  StreamSet s(1);
  Rng a = s.open("x");
  EXPECT_THROW(s.open("x"), std::logic_error);
  Rng b = StreamSet(1).open("x");
  EXPECT_EQ(a.next_u64(), b.next_u64());  // a name is a pure function of (name, seed)
}

TEST(Queries, MultiPrefSplitsEvenlyOverHumans) {
  const Dataset d = make_grid_dataset();
  const auto r = make_reward_sets(4, 1);
  Rng rng(5);
  const auto p = sample_preference_queries(d, 100, r.multipref50, Teacher{}, rng);
  ASSERT_EQ(p.count, 100);
  std::vector<int> per(50, 0);
  for (int h : p.human) ++per[h];
  for (int c : per) EXPECT_EQ(c, 2);
  // Labels agree with the reward of the human who answered.
  for (int i = 0; i < p.count; ++i) {
    const float* w = r.multipref50.weights.data() + 4 * p.human[i];
    const double ra = reward(w, d.feature(p.pairs[2 * i]), 4),
                 rb = reward(w, d.feature(p.pairs[2 * i + 1]), 4);
    if (ra != rb) {
      EXPECT_EQ(p.label[i], ra > rb ? 1.f : 0.f);
    }
  }
  const auto s = sample_similarity_queries(d, 50, Teacher{}, rng);
  ASSERT_EQ(s.idx.size(), 150u);
  for (int i = 0; i < 50; ++i) {
    auto dist = [&](int a, int b) {
      double t = 0;
      for (int k = 0; k < 4; ++k) t += std::pow(d.feature(a)[k] - d.feature(b)[k], 2);
      return t;
    };
    const int p1 = s.idx[3 * i], p2 = s.idx[3 * i + 1], n = s.idx[3 * i + 2];
    EXPECT_LE(dist(p1, p2), dist(p1, n));
    EXPECT_LE(dist(p1, p2), dist(p2, n));
  }
  const auto f = sample_fpe_split(d, 1000, rng);
  EXPECT_EQ(f.train.size(), 800u);
  EXPECT_EQ(f.test.size(), 200u);
  std::set<int> all(f.train.begin(), f.train.end());
  all.insert(f.test.begin(), f.test.end());
  EXPECT_EQ(all.size(), 1000u);
}

}  // namespace
}  // namespace sirl
