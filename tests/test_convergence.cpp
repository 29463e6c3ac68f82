// The one convergence rule (engine/convergence.h) on hand-made curves.
#include <gtest/gtest.h>

#include <vector>

#include "engine/convergence.h"

namespace sirl {
namespace {

// The one convergence rule (engine/convergence.h) on hand-made curves.
TEST(Convergence, ComparesTheLastTwoTenthsOfTheCurve) {
  std::vector<float> c(20, 5.f);  // 20 epochs: windows of 2
  c[16] = c[17] = 2.f, c[18] = c[19] = 1.f;
  Convergence v = check_convergence(c);
  EXPECT_EQ(v.window, 2);
  EXPECT_DOUBLE_EQ(v.relative_change, 0.5);  // (2 − 1) / 2
  EXPECT_FALSE(v.converged);
  c[16] = c[17] = 1.f, c[18] = c[19] = 0.995f;  // 0.5 % lower: within 1 %
  v = check_convergence(c);
  EXPECT_NEAR(v.relative_change, 0.005, 1e-6);
  EXPECT_TRUE(v.converged);
  c[18] = c[19] = 1.02f;  // rising by 2 %: not settled either
  EXPECT_FALSE(check_convergence(c).converged);
  EXPECT_TRUE(check_convergence(std::vector<float>(50, 0.f)).converged);  // a loss at 0
  EXPECT_FALSE(check_convergence({1.f}).converged);  // one epoch cannot be judged
  EXPECT_EQ(check_convergence({1.f}).window, 0);
  EXPECT_EQ(check_convergence(std::vector<float>(300, 1.f)).window, 30);
}

}  // namespace
}  // namespace sirl
