#include <gtest/gtest.h>

#include "kernels/linear_probe.h"
#include "kernels/rng.h"

namespace sirl {
namespace {

TEST(LinearProbe, RecoversAnExactAffineMap) {
  // Y = X·A + c with A = [[1, −2], [0.5, 3], [0, 1]], c = [4, −1]: test MSE ≈ 0.
  Rng rng(1);
  const int n = 50;
  std::vector<float> X(n * 3), Y(n * 2);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) X[i * 3 + k] = float(rng.normal());
    Y[i * 2 + 0] = X[i * 3] + 0.5f * X[i * 3 + 1] + 4;
    Y[i * 2 + 1] = -2 * X[i * 3] + 3 * X[i * 3 + 1] + X[i * 3 + 2] - 1;
  }
  auto p = fit_linear_probe(X.data(), Y.data(), 40, 3, 2);
  EXPECT_NEAR(p.weights[0 * 2 + 0], 1.0, 1e-5);
  EXPECT_NEAR(p.weights[1 * 2 + 1], 3.0, 1e-5);
  EXPECT_NEAR(p.weights[3 * 2 + 0], 4.0, 1e-5);  // bias row
  EXPECT_LT(linear_probe_mse(p, X.data() + 40 * 3, Y.data() + 40 * 2, 10), 1e-10);
}

TEST(LinearProbe, ConstantTargetGivesVarianceOfResidual) {
  // Inputs carry no information (all-zero, rank-deficient) → best fit is the training mean.
  // Train Y = {0, 2} (mean 1); test Y = {1, 3} → MSE = (0² + 2²)/2 = 2.
  std::vector<float> X(4, 0.f), Ytr = {0, 2}, Yte = {1, 3};
  auto p = fit_linear_probe(X.data(), Ytr.data(), 2, 2, 1);
  EXPECT_NEAR(linear_probe_mse(p, X.data(), Yte.data(), 2), 2.0, 1e-12);
}

TEST(LinearProbe, EmptySetIsAnError) {
  std::vector<float> X(2), Y(1);
  EXPECT_THROW(fit_linear_probe(X.data(), Y.data(), 0, 2, 1), std::invalid_argument);
}

}  // namespace
}  // namespace sirl
