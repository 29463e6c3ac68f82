// The symmetric triplet loss: hand-computed cases and its gradient against finite differences.
#include <gtest/gtest.h>

#include <vector>

#include "kernels/rng.h"
#include "kernels/triplet_loss.h"
#include "tests/grad_check.h"

namespace sirl {
namespace {

TEST(TripletLoss, HandComputedCases) {
  // 1-d embeddings, rows P1 | P2 | N, margin 1.
  // Triplet 0: p1=0, p2=1, n=3: d12=1, d1n=9, d2n=4 → both hinges inactive → 0.
  // Triplet 1: p1=0, p2=2, n=1: d12=4, d1n=1, d2n=1 → (4−1+1) + (4−1+1) = 8.
  std::vector<double> emb = {0, 0, 1, 2, 3, 1};
  std::vector<double> g(6);
  EXPECT_DOUBLE_EQ(symmetric_triplet_loss(emb.data(), 2, 1, 1.0, g.data()), 8.0 / 2);
  // Triplet 1 gradients / B: p1: 2(n−p2)+2(p1−p2) = −2−4 = −6; p2: 2(p2−p1)+2(n−p1) = 4+2 = 6;
  // n: 2(p1−n)+2(p2−n) = −2+2 = 0.
  EXPECT_DOUBLE_EQ(g[1], -3.0);
  EXPECT_DOUBLE_EQ(g[3], 3.0);
  EXPECT_DOUBLE_EQ(g[5], 0.0);
  EXPECT_DOUBLE_EQ(g[0], 0.0);
  EXPECT_DOUBLE_EQ(triplet_accuracy(emb.data(), 2, 1), 0.5);
  // Zero margin makes triplet 0's hinges still inactive and triplet 1's (4−1)·2 = 6.
  EXPECT_DOUBLE_EQ(symmetric_triplet_loss(emb.data(), 2, 1, 0.0, static_cast<double*>(nullptr)),
                   3.0);
}

TEST(TripletLoss, BatchOfThreeWithMarginIsTheMeanOfEachHinge) {
  // 1-d, margin 0.5, three triplets (rows P1 | P2 | N), each hinge by hand:
  //   t0: p1=0, p2=1, n=0.5: d12=1, d1n=0.25, d2n=0.25 → (1−0.25+0.5)·2 = 2.5
  //   t1: p1=0, p2=0.5, n=2: d12=0.25, d1n=4, d2n=2.25 → both < 0 → 0
  //   t2: p1=1, p2=0, n=1.5: d12=1, d1n=0.25, d2n=2.25 → (1−0.25+0.5) + max(1−2.25+0.5, 0)
  //       = 1.25 + 0 = 1.25 (one hinge active, the other not)
  // L = (2.5 + 0 + 1.25) / 3 = 1.25 (a sum would be 3.75; margin 0 would give 2.25 / 3).
  std::vector<double> emb = {0, 0, 1, 1, 0.5, 0, 0.5, 2, 1.5};
  std::vector<double> g(9);
  EXPECT_DOUBLE_EQ(symmetric_triplet_loss(emb.data(), 3, 1, 0.5, g.data()), 3.75 / 3);
  // t2's one active hinge, h1 = d(p1,p2) − d(p1,n): ∂/∂p1 = 2(p1−p2) − 2(p1−n) = 2 + 1 = 3,
  // ∂/∂p2 = −2(p1−p2) = −2, ∂/∂n = 2(p1−n) = −1; each over B = 3.
  EXPECT_DOUBLE_EQ(g[2], 3.0 / 3);
  EXPECT_DOUBLE_EQ(g[5], -2.0 / 3);
  EXPECT_DOUBLE_EQ(g[8], -1.0 / 3);
  EXPECT_DOUBLE_EQ(g[1], 0.0);  // t1 contributes nothing
  EXPECT_DOUBLE_EQ(triplet_max_hinge(emb.data(), 3, 1, 0.5), 1.25);
}

TEST(TripletLoss, GradientMatchesFiniteDifferences) {
  Rng rng(5);
  const int B = 7, d = 6;
  auto emb = test::random_vec(3 * B * d, rng, 0.5);
  std::vector<double> g(emb.size());
  symmetric_triplet_loss(emb.data(), B, d, 1.0, g.data());
  test::expect_gradient_matches(
      [&](const std::vector<double>& e) {
        return symmetric_triplet_loss(e.data(), B, d, 1.0, static_cast<double*>(nullptr));
      },
      emb, g);
}

}  // namespace
}  // namespace sirl
