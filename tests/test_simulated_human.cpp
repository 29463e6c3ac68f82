// The simulated human: similarity and preference oracles, noise models, Boltzmann rationality.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "datasets/grid_robot.h"
#include "datasets/queries.h"
#include "datasets/simulated_human.h"
#include "kernels/rng.h"

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

}  // namespace
}  // namespace sirl
