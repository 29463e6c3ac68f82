// Active selection of similarity queries: the two scores on hand-made cases, and the selection
// loop's contract — the budget exactly, no triplet asked twice, no trajectory twice in a batch,
// the teacher's own answers, picks that score above their pool, determinism and resume.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <set>

#include "datasets/grid_robot.h"
#include "engine/active_queries.h"
#include "tests/memory_checkpointer.h"

namespace sirl {
namespace {

TEST(ActiveScores, VoteEntropyByHand) {
  const int agree[5] = {1, 1, 1, 1, 1}, three_ways[3] = {0, 1, 2}, two_one[3] = {2, 0, 2};
  EXPECT_EQ(vote_entropy(agree, 5), 0.0);
  EXPECT_NEAR(vote_entropy(three_ways, 3), std::log(3.0), 1e-12);
  EXPECT_NEAR(vote_entropy(two_one, 3),
              -(2.0 / 3 * std::log(2.0 / 3) + 1.0 / 3 * std::log(1.0 / 3)), 1e-12);
}

TEST(ActiveScores, MutualInformationByHand) {
  // Members that agree (even when each is unsure) carry no information: 0.
  const double same[9] = {0.2, 0.5, 0.3, 0.2, 0.5, 0.3, 0.2, 0.5, 0.3};
  EXPECT_NEAR(mutual_information(same, 3), 0.0, 1e-12);
  // Three confident members naming three different pairs: H(1/3, 1/3, 1/3) − 0 = log 3.
  const double split[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  EXPECT_NEAR(mutual_information(split, 3), std::log(3.0), 1e-12);
  // Two members: (1, 0, 0) and (0.5, 0.5, 0): H(0.75, 0.25) − (0 + log 2)/2.
  const double two[6] = {1, 0, 0, 0.5, 0.5, 0};
  EXPECT_NEAR(mutual_information(two, 2),
              -(0.75 * std::log(0.75) + 0.25 * std::log(0.25)) - std::log(2.0) / 2, 1e-12);
}

TEST(ActiveScores, CrowdKernelReducesToTamuzForTwoOptions) {
  const double mu = 0.05, ab = 0.3, ac = 1.1, bc = 0.7;
  const auto p = crowd_kernel_probs({ab, ac, bc}, mu);
  EXPECT_NEAR(p[0] + p[1] + p[2], 1.0, 1e-12);
  EXPECT_GT(p[0], p[2]);
  EXPECT_GT(p[2], p[1]);  // the closer the pair, the likelier it is named
  // Of "(a, b) or (a, c)": Tamuz et al.'s (μ + δ_ac) / (2μ + δ_ab + δ_ac).
  EXPECT_NEAR(p[0] / (p[0] + p[1]), (mu + ac) / (2 * mu + ab + ac), 1e-12);
}

ActiveConfig small(Selection rule) {
  ActiveConfig c;
  c.rule = rule;
  c.budget = 110;  // 5 rounds of 25 would be 125: the last round asks only what is left
  c.members = 3;
  c.pool = 150;
  c.batch = 25;
  c.round_epochs = 4;
  c.hyper.phi_hidden = {16, 16};
  c.hyper.sirl.batch = 16;
  return c;
}

std::array<int32_t, 3> sorted_triple(const int32_t* t) {
  std::array<int32_t, 3> s{t[0], t[1], t[2]};
  std::sort(s.begin(), s.end());
  return s;
}

TEST(ActiveSelection, SpendsTheBudgetAsksNothingTwiceAndKeepsTheTeachersAnswers) {
  const Dataset d = make_grid_dataset();
  for (Selection rule : {Selection::vote, Selection::infogain}) {
    const ActiveQueries a = select_active_queries(d, Teacher{}, small(rule), 3);
    SCOPED_TRACE(selection_name(rule));
    ASSERT_EQ(a.queries.count, 110);
    ASSERT_EQ(a.queries.idx.size(), 330u);
    EXPECT_EQ(a.rounds, 5);  // 25 uniform, then 25, 25, 25 and the last 10
    std::set<std::array<int32_t, 3>> seen;
    for (int64_t i = 0; i < a.queries.count; ++i) {
      const int32_t* t = a.queries.idx.data() + 3 * i;
      EXPECT_TRUE(seen.insert(sorted_triple(t)).second) << "triplet " << i << " asked twice";
      // The perfect teacher's answer: (P1, P2) is the closest pair on the true features.
      auto dist = [&](int32_t x, int32_t y) {
        double s = 0;
        for (int f = 0; f < d.feature_count(); ++f)
          s += std::pow(d.feature(x)[f] - d.feature(y)[f], 2);
        return s;
      };
      EXPECT_LE(dist(t[0], t[1]), std::min(dist(t[0], t[2]), dist(t[1], t[2])) + 1e-9);
    }
    // Rounds after the first: no trajectory twice in one batch (the pool is big enough), and
    // the batch scores at least its pool's mean (the top of the ranking was taken).
    for (int r = 1; r < a.rounds; ++r) {
      std::set<int32_t> rows;
      const int64_t lo = 25 * r, hi = std::min<int64_t>(lo + 25, a.queries.count);
      for (int64_t i = 3 * lo; i < 3 * hi; ++i)
        EXPECT_TRUE(rows.insert(a.queries.idx[size_t(i)]).second) << "round " << r;
      EXPECT_GE(a.batch_score[size_t(r)], a.pool_score[size_t(r)]) << "round " << r;
    }
    EXPECT_GT(a.batch_score.back(), 0.f) << "the members never disagreed";
    // Deterministic: the same seed asks the same triplets.
    EXPECT_EQ(select_active_queries(d, Teacher{}, small(rule), 3).queries.idx, a.queries.idx);
  }
}

// A Ξ so small that the budget takes as many of its triplets as the selection accepts (budget +
// pool ≤ half of them: 16 trajectories, 560 unordered triplets, 220 asked, pools of 60): the
// later rounds' pools are often triplets already asked, and none may be asked again.
TEST(ActiveSelection, ATinyXiNearlyExhaustedStillAsksNothingTwice) {
  const Dataset full = make_grid_dataset();
  Dataset d = full;
  const int T = 16, F = full.feature_count();
  d.count = T;
  d.inputs.clear();
  d.features.clear();
  d.features_raw.clear();
  for (int i = 0; i < T; ++i) {
    const int64_t row = int64_t(i) * (full.count / T) + 3;  // spread over Ξ: distinct features
    d.inputs.insert(d.inputs.end(), full.input(row), full.input(row) + full.input_dim);
    d.features_raw.insert(d.features_raw.end(), full.features_raw.begin() + row * F,
                          full.features_raw.begin() + (row + 1) * F);
  }
  normalise_features(d);
  ActiveConfig c = small(Selection::vote);
  c.budget = 220;
  c.pool = 60;
  c.batch = 40;
  const ActiveQueries a = select_active_queries(d, Teacher{}, c, 5);
  ASSERT_EQ(a.queries.count, 220);
  std::set<std::array<int32_t, 3>> seen;
  for (int64_t i = 0; i < a.queries.count; ++i)
    EXPECT_TRUE(seen.insert(sorted_triple(a.queries.idx.data() + 3 * i)).second)
        << "triplet " << i << " asked twice";
}

using test::Interrupted;
using test::MemoryCheckpointer;

TEST(ActiveSelection, AKilledSelectionResumesToTheSameQueries) {
  const Dataset d = make_grid_dataset();
  const ActiveQueries plain = select_active_queries(d, Teacher{}, small(Selection::vote), 4);
  MemoryCheckpointer cp;
  cp.stop_after = 3;
  const ActiveConfig c = small(Selection::vote);
  EXPECT_THROW(select_active_queries(d, Teacher{}, c, 4, {.checkpointer = &cp}), Interrupted);
  cp.stop_after = -1;
  const ActiveQueries resumed = select_active_queries(d, Teacher{}, c, 4, {.checkpointer = &cp});
  EXPECT_EQ(resumed.queries.idx, plain.queries.idx);
  EXPECT_EQ(resumed.batch_score, plain.batch_score);
  EXPECT_EQ(resumed.train_flops, plain.train_flops);
}

TEST(ActiveSelection, RejectsConfigsThatCannotWork) {
  const Dataset d = make_grid_dataset();
  ActiveConfig c = small(Selection::vote);
  c.members = 1;
  EXPECT_THROW(select_active_queries(d, Teacher{}, c, 1), std::invalid_argument);
  c = small(Selection::vote);
  c.pool = 10;  // < batch
  EXPECT_THROW(select_active_queries(d, Teacher{}, c, 1), std::invalid_argument);
  EXPECT_THROW(parse_selection("bald"), std::invalid_argument);
  // A teacher who skips everything ends the selection with a message, not an endless loop.
  Teacher mute;
  mute.skip = 1e9;
  EXPECT_THROW(select_active_queries(d, mute, small(Selection::vote), 1), std::runtime_error);
  EXPECT_EQ(parse_selection("infogain"), Selection::infogain);
}

}  // namespace
}  // namespace sirl
