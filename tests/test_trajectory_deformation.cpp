// The trajectory deformation norm (K^T K) against a dense solve.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <vector>

#include "datasets/trajectory_deformation.h"

namespace sirl {
namespace {

TEST(DeformationNorm, IsKTransposeKAndSolvesLikeADenseSolve) {
  const int W = 7, n = 2, m = W - 2;
  DeformationNorm norm(W, n);
  // K [(m+2), m] per joint: column c has 1, −2, 1 at rows c, c+1, c+2.
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(m + 2, m);
  for (int c = 0; c < m; ++c) K(c, c) = 1, K(c + 1, c) = -2, K(c + 2, c) = 1;
  const Eigen::MatrixXd block = K.transpose() * K;
  const auto A = norm.dense_matrix();
  for (int j = 0; j < n; ++j)
    for (int r = 0; r < m; ++r)
      for (int c = 0; c < m; ++c) {
        EXPECT_EQ(A[(j * m + r) * norm.size() + j * m + c], block(r, c));
        for (int j2 = 0; j2 < n; ++j2)
          if (j2 != j) {
            EXPECT_EQ(A[(j * m + r) * norm.size() + j2 * m + c], 0.0);
          }
      }
  // A torque at one interior waypoint, solved by CHOLMOD and by a dense LLᵀ.
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(norm.size(), 3);
  B(2, 0) = 1.0;
  B(m + 1, 1) = -0.5;
  B(0, 2) = 0.3, B(m + m - 1, 2) = 0.7;
  Eigen::MatrixXd X = B;
  norm.solve(X.data(), 3);
  const Eigen::Map<const Eigen::MatrixXd> Ad(A.data(), norm.size(), norm.size());
  const Eigen::MatrixXd ref = Ad.llt().solve(B);
  EXPECT_LT((X - ref).cwiseAbs().maxCoeff(), 1e-10);
  // The deformation is smooth: it bends every interior waypoint, not just the pushed one.
  for (int i = 0; i < m; ++i) EXPECT_GT(X(i, 0), 0.0);
}

}  // namespace
}  // namespace sirl
