// Query sampling: distinct trajectories per query, reward sets, MultiPref's split over humans.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

#include "datasets/grid_robot.h"
#include "datasets/queries.h"
#include "datasets/query_bundle.h"
#include "kernels/rng.h"

namespace sirl {
namespace {

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

// TPA measures generalisation: a held-out pair that repeats one of that reward's training pairs
// (in either order) would be scored on what the head was fit to. On GridRobot's Ξ with quick's
// budget (250 pairs per reward, 200 of them training) and every test reward, none does.
TEST(Queries, TpaHeldOutPairsNeverRepeatTheirTrainingPairs) {
  const Dataset d = make_grid_dataset();
  QueryBundleConfig c;
  c.similarity = 100;
  c.preference = 100;
  c.tpa_pairs = 250;
  for (uint64_t seed : {0, 1, 2, 3, 4}) {
    const QueryBundle b = make_query_bundle(d, c, seed);
    ASSERT_FALSE(b.tpa.empty());
    int64_t held_out = 0;
    for (const TpaSet& t : b.tpa) {
      ASSERT_EQ(t.train, 200);
      std::set<std::pair<int32_t, int32_t>> train;
      for (int64_t i = 0; i < t.train; ++i) {
        const int32_t a = t.pairs.pairs[2 * i], bb = t.pairs.pairs[2 * i + 1];
        train.insert({std::min(a, bb), std::max(a, bb)});
      }
      for (int64_t i = t.train; i < t.pairs.count; ++i, ++held_out) {
        const int32_t a = t.pairs.pairs[2 * i], bb = t.pairs.pairs[2 * i + 1];
        EXPECT_EQ(train.count({std::min(a, bb), std::max(a, bb)}), 0u)
            << "seed " << seed << ": held-out pair " << i << " (" << a << ", " << bb
            << ") is a training pair";
      }
    }
    EXPECT_EQ(held_out, int64_t(b.tpa.size()) * 50);
  }
}

// The same rule where repeats are certain if allowed: 12 trajectories have 66 unordered pairs; 40
// training pairs and 20 held out per reward. Every held-out pair is new, and a reward whose
// training draw repeats nothing keeps the held-out pairs it would have drawn without the rule
// (they are the same stream's next draws).
TEST(Queries, TpaHeldOutPairsAreDrawnAgainWhenTheyRepeatATrainingPair) {
  const Dataset full = make_grid_dataset();
  Dataset d = full;
  d.count = 12;
  d.inputs.resize(size_t(12) * d.input_dim);
  d.features.resize(size_t(12) * d.feature_count());
  d.features_raw.resize(size_t(12) * d.feature_count());
  const RewardSets r = make_reward_sets(d.feature_count(), 3);
  int redrawn = 0;
  for (int row = 0; row < r.test.count; ++row) {
    Rng rng(100 + row);
    const TpaSet t = sample_tpa_set(d, 60, r.test, row, Teacher{}, rng);
    ASSERT_EQ(t.train, 48);
    std::set<std::pair<int32_t, int32_t>> train;
    for (int64_t i = 0; i < t.train; ++i)
      train.insert({std::min(t.pairs.pairs[2 * i], t.pairs.pairs[2 * i + 1]),
                    std::max(t.pairs.pairs[2 * i], t.pairs.pairs[2 * i + 1])});
    // The draws without the rule: the same stream, pairs of distinct rows, nothing skipped.
    Rng plain(100 + row);
    std::vector<std::pair<int32_t, int32_t>> draws;
    for (int i = 0; i < 60 + 200; ++i) {
      const int32_t a = int32_t(plain.uniform_int(d.count));
      int32_t b;
      do b = int32_t(plain.uniform_int(d.count));
      while (b == a);
      draws.push_back({a, b});
    }
    size_t next = size_t(t.train);
    for (int64_t i = t.train; i < t.pairs.count; ++i) {
      const int32_t a = t.pairs.pairs[2 * i], b = t.pairs.pairs[2 * i + 1];
      EXPECT_EQ(train.count({std::min(a, b), std::max(a, b)}), 0u) << "reward " << row;
      // It is the first later draw that is not a training pair.
      while (train.count({std::min(draws[next].first, draws[next].second),
                          std::max(draws[next].first, draws[next].second)})) {
        ++next;
        ++redrawn;
      }
      EXPECT_EQ(std::make_pair(a, b), draws[next]) << "reward " << row << " pair " << i;
      ++next;
    }
  }
  EXPECT_GT(redrawn, 20);  // 48 of 66 pairs train: most rewards had to draw again
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
