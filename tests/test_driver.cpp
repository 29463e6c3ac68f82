// datasets/driver: the car's dynamics and features against hand-computed cases (the authors'
// definitions in docs/driver.md), and Ξ's properties.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "datasets/driver.h"

namespace sirl {
namespace {

constexpr double kHalfPi = std::numbers::pi / 2;

TEST(Driver, NoControlsDriveStraightAndSlowDownByFriction) {
  const DriverRollout r = drive({});
  // v' = −v: each step multiplies the speed by 1 − dt = 0.9; the heading never turns.
  double v = 0.4, y = -0.3, speed = 0;
  for (int t = 0; t < kDriverSteps; ++t) {
    y += 0.1 * v;  // the old speed moves the car (forward Euler)
    v *= 0.9;
    EXPECT_NEAR(r.car[t][0], 0.0, 1e-15) << t;
    EXPECT_NEAR(r.car[t][1], y, 1e-12) << t;
    EXPECT_DOUBLE_EQ(r.car[t][2], kHalfPi) << t;
    EXPECT_NEAR(r.car[t][3], v, 1e-12) << t;
    speed += (v - 1) * (v - 1);
  }
  EXPECT_NEAR(r.features[0], 1.0, 1e-12);  // in the middle lane's centre all along
  EXPECT_NEAR(r.features[1], speed / 50, 1e-12);
  EXPECT_NEAR(r.features[2], 1.0, 1e-12);  // sin(π/2)
}

TEST(Driver, TheOtherCarChangesLaneAtItsScriptedSteps) {
  const DriverRollout r = drive({});
  // Steps 0–9: straight at 0.41, which its acceleration 0.41 holds (v' = 0.41 − v = 0).
  EXPECT_NEAR(r.other[0][1], 0.041, 1e-12);
  EXPECT_NEAR(r.other[9][1], 0.41, 1e-12);
  EXPECT_NEAR(r.other[9][0], 0.17, 1e-12);
  // Steps 10–19 steer left (u0 = 1): the heading grows by dt·v·1 = 0.041 a step.
  EXPECT_NEAR(r.other[10][2], kHalfPi + 0.041, 1e-12);
  EXPECT_NEAR(r.other[19][2], kHalfPi + 0.41, 1e-12);
  // Steps 20–29 steer back (u0 = −1): straight again, moved left of its lane.
  EXPECT_NEAR(r.other[29][2], kHalfPi, 1e-12);
  EXPECT_LT(r.other[29][0], 0.17 - 0.05);
  // Steps 30–49 accelerate with 0.41·1.3: v' = 0.533 − v > 0.
  EXPECT_NEAR(r.other[30][3], 0.41 + 0.1 * (0.533 - 0.41), 1e-12);
  // Collision feature of the straight car: the mean of exp(−(7dx² + 3dy²)), computed here.
  double c = 0;
  for (int t = 0; t < kDriverSteps; ++t) {
    const double dx = r.car[t][0] - r.other[t][0], dy = r.car[t][1] - r.other[t][1];
    c += std::exp(-(7 * dx * dx + 3 * dy * dy));
  }
  EXPECT_NEAR(r.features[3], c / 50, 1e-12);
}

TEST(Driver, SteeringTurnsTheCarAndTheLaneFeatureFallsBetweenLanes) {
  std::array<double, 2 * kDriverSegments> u{};
  u[0] = 1;  // steer left for the first 10 steps
  const DriverRollout r = drive(u);
  EXPECT_NEAR(r.car[0][2], kHalfPi + 0.1 * 0.4, 1e-12);  // θ' = v·u0
  EXPECT_LT(r.car[49][0], -0.05);                        // it left the middle lane to the left
  EXPECT_LT(r.features[0], 0.99);
  EXPECT_LT(r.features[2], 1.0);  // sin θ < 1 once turned
  // Halfway between two lane centres (x = ±0.085) the lane term is exp(−30·0.085²) ≈ 0.805.
  EXPECT_NEAR(std::exp(-30 * 0.085 * 0.085), 0.805, 1e-3);
}

TEST(Driver, XiIsDeterministicNormalisedAndAPrefixOfALargerXi) {
  const Dataset a = make_driver_dataset({200, 7}), b = make_driver_dataset({300, 7});
  const Dataset c = make_driver_dataset({200, 8});
  ASSERT_EQ(a.count, 200);
  ASSERT_EQ(a.input_dim, kDriverInputDim);
  ASSERT_EQ(a.feature_count(), 4);
  for (size_t i = 0; i < a.inputs.size(); ++i) ASSERT_EQ(a.inputs[i], b.inputs[i]) << i;
  for (size_t i = 0; i < a.features_raw.size(); ++i)
    ASSERT_EQ(a.features_raw[i], b.features_raw[i]) << i;
  EXPECT_NE(a.inputs, c.inputs);  // another data seed, other controls
  for (int f = 0; f < 4; ++f) {
    float lo = 1, hi = 0;
    for (int64_t k = 0; k < a.count; ++k) {
      lo = std::min(lo, a.feature(k)[f]);
      hi = std::max(hi, a.feature(k)[f]);
    }
    EXPECT_EQ(lo, 0.f) << f;
    EXPECT_EQ(hi, 1.f) << f;
  }
  // Each trajectory's points: its start, then the (x, y) of the states in its input.
  ASSERT_EQ(a.point_len, kDriverSteps + 1);
  EXPECT_FLOAT_EQ(a.points[1], -0.3f);
  for (int t = 0; t < kDriverSteps; ++t) {
    EXPECT_EQ(a.points[2 * (t + 1)], a.inputs[4 * t]);
    EXPECT_EQ(a.points[2 * (t + 1) + 1], a.inputs[4 * t + 1]);
  }
  EXPECT_THROW(make_driver_dataset({2, 0}), std::invalid_argument);
}

}  // namespace
}  // namespace sirl
