// The Bradley–Terry preference loss and accuracy: hand-computed cases, gradient, ties.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "kernels/bradley_terry_loss.h"
#include "kernels/rng.h"
#include "tests/grad_check.h"

namespace sirl {
namespace {

TEST(BradleyTerry, HandComputedCases) {
  // r_A = 1, r_B = 0, A preferred: −log σ(1) = log(1 + e^−1) = 0.313261687518...
  std::vector<double> r = {1, 0}, l = {1}, g(2);
  EXPECT_NEAR(bradley_terry_loss(r.data(), l.data(), 1, 0.0, g.data()), 0.31326168751822286, 1e-15);
  EXPECT_NEAR(g[0], -1 / (1 + std::exp(1.0)), 1e-15);  // σ(1) − 1 = −1/(1 + e)
  // L2 weight 0.5 adds 0.5 · (1² + 0²) = 0.5 and 2·0.5·r to the gradient.
  EXPECT_NEAR(bradley_terry_loss(r.data(), l.data(), 1, 0.5, g.data()), 0.81326168751822286, 1e-15);
  EXPECT_NEAR(g[0], -1 / (1 + std::exp(1.0)) + 1.0, 1e-15);
  // A tie label 0.5 at z = 0 gives log 2, the maximum-entropy answer.
  std::vector<double> r0 = {0.3, 0.3}, half = {0.5};
  EXPECT_NEAR(bradley_terry_loss(r0.data(), half.data(), 1, 0.0, g.data()), std::log(2.0), 1e-15);
  // Huge margins stay finite.
  std::vector<double> big = {800, -800};
  std::vector<double> wrong = {0};
  EXPECT_NEAR(bradley_terry_loss(big.data(), wrong.data(), 1, 0.0, g.data()), 1600.0, 1e-9);
}

TEST(BradleyTerry, BatchOfThreeWithATieAtANonZeroMarginIsTheMean) {
  // z = r_A − r_B: pair 0 z = 2 (label 1), pair 1 z = −1 (label 0), pair 2 z = 1 (label 0.5).
  //   −log σ(2) = log(1+e^−2); −log σ(1) = log(1+e^−1) (label 0 at z = −1);
  //   the tie: −½ log σ(1) − ½ log σ(−1) = ½ log(1+e^−1) + ½ log(1+e) .
  const double a = std::log1p(std::exp(-2.0)), b = std::log1p(std::exp(-1.0)),
               c = 0.5 * std::log1p(std::exp(-1.0)) + 0.5 * std::log1p(std::exp(1.0));
  std::vector<double> r = {2, 0, 1, 0, 1, 0}, l = {1, 0, 0.5}, g(6);
  EXPECT_NEAR(bradley_terry_loss(r.data(), l.data(), 3, 0.0, g.data()), (a + b + c) / 3, 1e-15);
  // ∂L/∂r_A = (σ(z) − ℓ)/B: the tie's is (σ(1) − 0.5)/3 > 0, not (σ(1) − 1)/3.
  const double s1 = 1 / (1 + std::exp(-1.0));
  EXPECT_NEAR(g[2], (s1 - 0.5) / 3, 1e-15);
  EXPECT_NEAR(g[5], -(s1 - 0.5) / 3, 1e-15);
  // With L2 weight 0.25: + 0.25 · (4 + 0 + 1 + 0 + 1 + 0) / 3.
  EXPECT_NEAR(bradley_terry_loss(r.data(), l.data(), 3, 0.25, g.data()),
              (a + b + c) / 3 + 0.25 * 6 / 3, 1e-15);
  // Accuracy: pair 0 right, pair 1 right (z < 0, label 0), the tie skipped: 2 of 2.
  EXPECT_DOUBLE_EQ(preference_accuracy(r.data(), l.data(), 3), 1.0);
}

TEST(BradleyTerry, GradientMatchesFiniteDifferences) {
  Rng rng(9);
  const int B = 8;
  auto r = test::random_vec(2 * B, rng, 2.0);
  std::vector<double> l(B);
  for (int i = 0; i < B; ++i) l[i] = i % 3 == 0 ? 0.5 : double(i % 2);
  std::vector<double> g(2 * B);
  bradley_terry_loss(r.data(), l.data(), B, 10.0, g.data());
  test::expect_gradient_matches(
      [&](const std::vector<double>& x) {
        return bradley_terry_loss(x.data(), l.data(), B, 10.0, static_cast<double*>(nullptr));
      },
      r, g);
}

TEST(BradleyTerry, AccuracyCountsAgreement) {
  std::vector<float> r = {2, 0, 1, /*B:*/ 1, 1, 5}, l = {1, 1, 0};
  // pair 0: 2 > 1, A preferred → right; pair 1: 0 < 1, A preferred → wrong; pair 2: 1 < 5, B →
  // right
  EXPECT_DOUBLE_EQ(preference_accuracy(r.data(), l.data(), 3), 2.0 / 3);
}

TEST(BradleyTerry, AccuracySkipsTiedAnswersAndCountsEqualRewardsAsWrong) {
  // Pairs 1 and 3 are answered "equal" (0.5): skipped, not counted right or wrong. Pair 2 has
  // equal predicted rewards for a strict answer: not a win for A, so right only if B preferred.
  std::vector<float> r = {2, 0, 3, 9, /*B:*/ 1, 1, 3, 0}, l = {1, 0.5f, 1, 0.5f};
  EXPECT_DOUBLE_EQ(preference_accuracy(r.data(), l.data(), 4), 1.0 / 2);  // 1 right of 2
  l = {0.5f, 0.5f, 0.5f, 0.5f};
  EXPECT_DOUBLE_EQ(preference_accuracy(r.data(), l.data(), 4), 0.0);  // nothing to score
}

}  // namespace
}  // namespace sirl
