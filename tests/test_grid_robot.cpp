#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "datasets/grid_robot.h"

namespace sirl {
namespace {

TEST(GridRobot, EnumerationCountIsCombinatorial) {
  const Dataset d = make_grid_dataset();
  // 4 ordered corner pairs × C(8,4) monotone paths × 7 angles.
  EXPECT_EQ(d.count, 4 * 70 * 7);
  EXPECT_EQ(d.input_dim, 19);
  EXPECT_EQ(d.inputs.size(), size_t(d.count) * 19);
  // All trajectories distinct, every path connected by unit moves, ends at opposite corners.
  std::set<std::vector<float>> uniq;
  for (int64_t i = 0; i < d.count; ++i) {
    const float* x = d.input(i);
    uniq.insert(std::vector<float>(x, x + 19));
    for (int s = 0; s < 8; ++s) {
      const float dx = std::abs(x[2 * s + 2] - x[2 * s]) * 4,
                  dy = std::abs(x[2 * s + 3] - x[2 * s + 1]) * 4;
      ASSERT_FLOAT_EQ(dx + dy, 1.f) << "trajectory " << i << " step " << s;
    }
    EXPECT_FLOAT_EQ(std::abs(x[16] - x[0]), 1.f);
    EXPECT_FLOAT_EQ(std::abs(x[17] - x[1]), 1.f);
    EXPECT_LE(std::abs(x[18]), 1.f);
  }
  EXPECT_EQ(uniq.size(), size_t(d.count));
}

// grid2, the paper's Fig. 3 environment: GridRobot's Ξ with only the laptop and the angle.
TEST(GridRobot, SimplifiedVariantKeepsOnlyTheLaptopAndTheAngle) {
  const Dataset g = make_grid2_dataset();
  EXPECT_EQ(g.env, "grid2");
  EXPECT_EQ(g.feature_names, (std::vector<std::string>{"laptop_distance", "abs_angle"}));
  EXPECT_EQ(g.object_names, (std::vector<std::string>{"laptop"}));
  EXPECT_EQ(g.count, 1960);
  // Hand check on every trajectory: the mean distance to the laptop cell (2,2) over the 9
  // states, and |angle|, recomputed from the inputs themselves.
  for (int64_t i = 0; i < g.count; ++i) {
    const float* x = g.input(i);
    double lap = 0;
    for (int s = 0; s < 9; ++s) lap += std::hypot(x[2 * s] * 4 - 2.0, x[2 * s + 1] * 4 - 2.0);
    ASSERT_NEAR(g.features_raw[2 * i], lap / 9, 1e-5) << i;
    ASSERT_NEAR(g.features_raw[2 * i + 1], std::abs(x[18]) * 90, 1e-4) << i;
  }
  // Normalised over Ξ to exactly [0, 1] per feature.
  for (int f = 0; f < 2; ++f) {
    float lo = 1, hi = 0;
    for (int64_t i = 0; i < g.count; ++i)
      lo = std::min(lo, g.feature(i)[f]), hi = std::max(hi, g.feature(i)[f]);
    EXPECT_FLOAT_EQ(lo, 0.f);
    EXPECT_FLOAT_EQ(hi, 1.f);
  }
}

TEST(GridRobot, FeaturesOnHandWorkedPath) {
  GridConfig c;  // obstacles (1,3), (3,1), laptop (2,2)
  // Along the bottom edge then up the right edge: (0,0)…(4,0),(4,1)…(4,4).
  std::array<std::array<int, 2>, kGridStates> cells{
      {{0, 0}, {1, 0}, {2, 0}, {3, 0}, {4, 0}, {4, 1}, {4, 2}, {4, 3}, {4, 4}}};
  const auto f = grid_features(c, cells, -60);
  // Distances to the laptop (2,2): √8, √5, 2, √5, √8, √5, 2, √5, √8.
  const double laptop = (3 * std::sqrt(8.0) + 4 * std::sqrt(5.0) + 2 * 2.0) / 9;
  // To obstacle 2 (3,1): √10, √5, √2, 1, √2, 1, √2, √5, √10.
  const double obs2 = (2 * std::sqrt(10.0) + 2 * std::sqrt(5.0) + 3 * std::sqrt(2.0) + 2.0) / 9;
  // To obstacle 1 (1,3): √10, 3, √10, √13, √18, √13, √10, 3, √10.
  const double obs1 = (4 * std::sqrt(10.0) + 2 * 3.0 + 2 * std::sqrt(13.0) + std::sqrt(18.0)) / 9;
  EXPECT_NEAR(f[0], obs1, 1e-6);
  EXPECT_NEAR(f[1], obs2, 1e-6);
  EXPECT_NEAR(f[2], laptop, 1e-6);
  EXPECT_FLOAT_EQ(f[3], 60.f);
}

TEST(GridRobot, NormalisedFeaturesSpanUnitInterval) {
  const Dataset d = make_grid_dataset();
  for (int f = 0; f < 4; ++f) {
    float lo = 1e9f, hi = -1e9f;
    for (int64_t i = 0; i < d.count; ++i) {
      lo = std::min(lo, d.feature(i)[f]);
      hi = std::max(hi, d.feature(i)[f]);
      // normalised = (raw − min)/(max − min)
      ASSERT_NEAR(
          d.feature(i)[f],
          (d.features_raw[i * 4 + f] - d.feature_min[f]) / (d.feature_max[f] - d.feature_min[f]),
          1e-6);
    }
    EXPECT_FLOAT_EQ(lo, 0.f);
    EXPECT_FLOAT_EQ(hi, 1.f);
  }
  EXPECT_FLOAT_EQ(d.feature_max[3], 90.f);
  EXPECT_FLOAT_EQ(d.feature_min[3], 0.f);
}

TEST(GridRobot, ObjectsAreConfigurableAndValidated) {
  // Ξ is closed under the 180° rotation (x, y) → (4 − x, 4 − y), which swaps opposite corners,
  // so the distances to (0,0) and to (4,4) take the same range over Ξ.
  GridConfig c;
  c.laptop = {0, 0};
  c.obstacle1 = {4, 4};
  const Dataset d = make_grid_dataset(c);
  EXPECT_FLOAT_EQ(d.object_positions[4], 0.f);
  EXPECT_FLOAT_EQ(d.object_positions[0], 4.f);
  EXPECT_FLOAT_EQ(d.feature_min[2], d.feature_min[0]);
  EXPECT_FLOAT_EQ(d.feature_max[2], d.feature_max[0]);
  // A corner laptop is farther on average than the centre one (default config).
  EXPECT_GT(d.feature_max[2], make_grid_dataset().feature_max[2]);
  c.laptop = {5, 0};
  EXPECT_THROW(make_grid_dataset(c), std::invalid_argument);
  c.laptop = {2, 2};
  c.size = 6;
  EXPECT_THROW(make_grid_dataset(c), std::invalid_argument);
}

}  // namespace
}  // namespace sirl
