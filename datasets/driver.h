// Driver: the autonomous-driving environment of active preference-based reward learning, as
// Bıyık and Sadigh's "Batch Active Preference-Based Learning of Reward Functions" (CoRL 2018)
// defines it (code: Stanford-ILIAD/batch-active-preference-based-learning, files simulator.py,
// models.py and dynamics.py; unchanged in their later easy-active-learning and
// DPP-Batch-Active-Learning code). It descends from Sadigh et al. (RSS 2017), whose own code
// (dsadigh/driving-preferences) uses 5 steps of 0.2 s, lanes 0.13 wide and 5 summed features;
// this is the CoRL 2018 version, the one later work benchmarks on. Constants and their sources:
// docs/driver.md.
//
// A car on a three-lane road heading +y (lane centres x = −0.17, 0, 0.17) shares it with another
// car that starts in the right lane and changes into the middle one in front of it. A trajectory
// is 5 control segments (steering, acceleration), each uniform in [−1, 1] and held for 10 steps
// of dt = 0.1 through the car's dynamics (forward Euler: ẋ = v cos θ, ẏ = v sin θ, θ̇ = v·u0,
// v̇ = u1 − v), 50 states from the start [0, −0.3, π/2, 0.4].
//
// Input vector (200 floats): for each of the 50 states after a step, (x, y, θ − π/2, v).
// True features φ* (raw, means over the 50 states, as the authors define them):
//   lane      exp(−30 · min((x − 0.17)², x², (x + 0.17)²))   staying in a lane
//   speed     (v − 1)²                                       off the target speed 1
//   heading   sin θ                                           heading along the road
//   collision exp(−(7 (x − x_h)² + 3 (y − y_h)²))            near the other car (x_h, y_h)
// normalised min-max over Ξ as every environment's are.
#pragma once
#include <array>
#include <cstdint>

#include "datasets/dataset.h"

namespace sirl {

struct DriverConfig {
  int64_t trajectories = 2000;  // Ξ: sampled control sequences
  uint64_t seed = 0;            // the data seed they are drawn from
};

inline constexpr int kDriverSegments = 5;
inline constexpr int kDriverStepsPerSegment = 10;
inline constexpr int kDriverSteps = kDriverSegments * kDriverStepsPerSegment;  // 50
inline constexpr int kDriverStateDim = 4;                                      // x, y, θ, v
inline constexpr int kDriverInputDim = kDriverSteps * kDriverStateDim;         // 200

// The 50 states (after each step) of the car driven by `controls` (steer₁, accel₁, …, steer₅,
// accel₅), and its 4 raw features; exposed for tests.
struct DriverRollout {
  std::array<std::array<double, 4>, kDriverSteps> car, other;  // (x, y, θ, v) after each step
  std::array<double, 4> features;                              // lane, speed, heading, collision
};
DriverRollout drive(const std::array<double, 2 * kDriverSegments>& controls);

// Throws std::invalid_argument for fewer than 3 trajectories.
Dataset make_driver_dataset(const DriverConfig& cfg);

}  // namespace sirl
