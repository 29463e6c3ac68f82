#include <gtest/gtest.h>

#include <cmath>

#include "kernels/rng.h"

namespace sirl {
namespace {

TEST(Rng, SameSeedSameStream) {
  Rng a(123), b(123), c(124);
  for (int i = 0; i < 10; ++i) {
    const auto x = a.next_u64();
    EXPECT_EQ(x, b.next_u64());
    EXPECT_NE(x, c.next_u64());
  }
}

TEST(Rng, MomentsOfUniformAndNormal) {
  Rng r(7);
  const int n = 200000;
  double su = 0, sn = 0, sn2 = 0;
  for (int i = 0; i < n; ++i) {
    su += r.uniform();
    const double z = r.normal();
    sn += z;
    sn2 += z * z;
  }
  // Standard errors: uniform mean 0.29/√n ≈ 6.5e-4, normal mean 1/√n ≈ 2.2e-3, var √2/√n ≈ 3.2e-3.
  EXPECT_NEAR(su / n, 0.5, 4e-3);
  EXPECT_NEAR(sn / n, 0.0, 1e-2);
  EXPECT_NEAR(sn2 / n, 1.0, 1.5e-2);
}

TEST(Rng, UniformIntCoversRangeEvenly) {
  Rng r(3);
  std::vector<int> counts(7, 0);
  for (int i = 0; i < 70000; ++i) ++counts[r.uniform_int(7)];
  for (int c : counts) EXPECT_NEAR(c, 10000, 400);  // ±4σ
}

TEST(Rng, KeySeedsDiffer) {
  EXPECT_EQ(seed_from_key("grid/sirl/N=100/seed=0"), seed_from_key("grid/sirl/N=100/seed=0"));
  EXPECT_NE(seed_from_key("grid/sirl/N=100/seed=0"), seed_from_key("grid/sirl/N=100/seed=1"));
}

}  // namespace
}  // namespace sirl
