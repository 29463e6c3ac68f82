// Central finite differences in double precision for the gradient-check tests.
// With h = 1e-6 the truncation error is O(h²) ≈ 1e-12 and the rounding error ≈ 1e-16/h ≈ 1e-10,
// so analytic and numeric gradients must agree to ~1e-7 relative; we assert 1e-6.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "kernels/rng.h"

namespace sirl::test {

// n draws of scale·N(0, 1).
inline std::vector<double> random_vec(size_t n, Rng& rng, double scale = 1.0) {
  std::vector<double> v(n);
  for (auto& x : v) x = scale * rng.normal();
  return v;
}

// f(x) is a scalar function of the vector x; `analytic` its claimed gradient at x.
inline void expect_gradient_matches(const std::function<double(const std::vector<double>&)>& f,
                                    std::vector<double> x, const std::vector<double>& analytic,
                                    double rel_tol = 1e-6, double h = 1e-6) {
  ASSERT_EQ(x.size(), analytic.size());
  double max_err = 0, scale = 1e-3;
  for (double g : analytic) scale = std::max(scale, std::abs(g));
  for (size_t i = 0; i < x.size(); ++i) {
    const double x0 = x[i];
    x[i] = x0 + h;
    const double fp = f(x);
    x[i] = x0 - h;
    const double fm = f(x);
    x[i] = x0;
    const double num = (fp - fm) / (2 * h);
    max_err = std::max(max_err, std::abs(num - analytic[i]));
    EXPECT_NEAR(analytic[i], num, rel_tol * scale) << "component " << i;
  }
  ::testing::Test::RecordProperty("max_abs_gradient_error", std::to_string(max_err));
}

}  // namespace sirl::test
