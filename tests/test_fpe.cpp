// Feature prediction error (FPE): a linear probe from φ to the true features, on held-out rows.
#include <gtest/gtest.h>

#include "engine/fpe.h"
#include "tests/grid_world.h"

namespace sirl {
namespace {

using namespace test;

// FPE scores the probe on the held-out rows and train_mse on the training rows: with φ = the true
// features the probe is exact (≈ 0); corrupting the targets of the test rows moves FPE and not
// train_mse, corrupting the training rows' targets moves train_mse.
TEST(Fpe, IsMeasuredOnTheHeldOutRowsOnly) {
  World w = world();
  const Representation phi = true_feature_phi(w.d);  // inputs = the clean features from here on
  const FpeSplit& split = w.bundle.fpe;
  const FpeResult clean = evaluate_fpe(phi, w.d, split);
  EXPECT_LT(clean.fpe, 1e-8);
  EXPECT_LT(clean.train_mse, 1e-8);
  Dataset test_noise = w.d;
  for (int32_t row : split.test)
    for (int f = 0; f < 4; ++f) test_noise.features[size_t(row) * 4 + f] = 1 - w.d.feature(row)[f];
  const FpeResult t = evaluate_fpe(phi, test_noise, split);
  EXPECT_GT(t.fpe, 0.01);
  EXPECT_EQ(t.train_mse, clean.train_mse);
  Dataset train_noise = w.d;  // targets shuffled among the training rows: no linear fit exists
  for (size_t i = 0; i < split.train.size(); ++i)
    for (int f = 0; f < 4; ++f)
      train_noise.features[size_t(split.train[i]) * 4 + f] =
          w.d.feature(split.train[(i * 7919 + 13) % split.train.size()])[f];
  EXPECT_GT(evaluate_fpe(phi, train_noise, split).train_mse, 0.01);
}

}  // namespace
}  // namespace sirl
