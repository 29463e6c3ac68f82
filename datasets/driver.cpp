#include "datasets/driver.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "kernels/rng.h"

namespace sirl {

namespace {

constexpr double kDt = 0.1;          // simulator.py: CarDynamics(0.1)
constexpr double kFriction = 1.0;    // dynamics.py: friction = 1
constexpr double kLaneWidth = 0.17;  // simulator.py: StraightLane([0,-1],[0,1],0.17) and ±1 lane
constexpr double kTargetSpeed = 1.0;
constexpr double kHalfPi = std::numbers::pi / 2;

using State = std::array<double, 4>;

// One forward-Euler step of dynamics.py's CarDynamics (every derivative from the old state).
State step(const State& s, double steer, double accel) {
  return {s[0] + kDt * s[3] * std::cos(s[2]), s[1] + kDt * s[3] * std::sin(s[2]),
          s[2] + kDt * s[3] * steer, s[3] + kDt * (accel - kFriction * s[3])};
}

// The other car's controls at step i (simulator.py): straight, then a lane change to the left
// and a speed-up.
std::array<double, 2> other_controls(int i) {
  if (i < 10) return {0., 0.41};
  if (i < 20) return {1., 0.41};
  if (i < 30) return {-1., 0.41};
  return {0., 0.41 * 1.3};
}

}  // namespace

DriverRollout drive(const std::array<double, 2 * kDriverSegments>& u) {
  DriverRollout r{};
  State car{0., -0.3, kHalfPi, 0.4}, other{kLaneWidth, 0., kHalfPi, 0.41};
  double lane = 0, speed = 0, heading = 0, collision = 0;
  for (int i = 0; i < kDriverSteps; ++i) {
    const int seg = i / kDriverStepsPerSegment;
    car = step(car, u[2 * seg], u[2 * seg + 1]);
    const auto oc = other_controls(i);
    other = step(other, oc[0], oc[1]);
    r.car[i] = car;
    r.other[i] = other;
    const double x = car[0];
    lane += std::exp(-30. * std::min({(x - kLaneWidth) * (x - kLaneWidth), x * x,
                                      (x + kLaneWidth) * (x + kLaneWidth)}));
    speed += (car[3] - kTargetSpeed) * (car[3] - kTargetSpeed);
    heading += std::sin(car[2]);
    const double dx = car[0] - other[0], dy = car[1] - other[1];
    collision += std::exp(-(7. * dx * dx + 3. * dy * dy));
  }
  r.features = {lane / kDriverSteps, speed / kDriverSteps, heading / kDriverSteps,
                collision / kDriverSteps};
  return r;
}

Dataset make_driver_dataset(const DriverConfig& cfg) {
  if (cfg.trajectories < 3)
    throw std::invalid_argument("driver: trajectories must be >= 3 (a similarity query needs 3)");
  Dataset d;
  d.env = "driver";
  d.seed = cfg.seed;
  d.count = cfg.trajectories;
  d.input_dim = kDriverInputDim;
  d.input_description =
      "for each of the 50 states after a step (dt 0.1 s): x, y (road units), heading − π/2 (rad), "
      "speed";
  d.feature_names = {"lane", "speed", "heading", "collision"};
  d.feature_units = {"", "(speed units)^2", "", ""};
  d.object_units = "road units";
  d.object_dim = 2;
  d.point_len = kDriverSteps + 1;
  d.point_dim = 2;
  d.inputs.resize(size_t(d.count) * kDriverInputDim);
  d.features_raw.resize(size_t(d.count) * 4);
  d.points.resize(size_t(d.count) * size_t(d.point_len) * 2);
  for (int64_t k = 0; k < d.count; ++k) {
    // One stream per trajectory: Ξ's first n trajectories are the same for every size.
    Rng rng(seed_from_key("driver/controls/" + std::to_string(k), cfg.seed));
    std::array<double, 2 * kDriverSegments> u{};
    for (double& c : u) c = rng.uniform(-1., 1.);
    const DriverRollout r = drive(u);
    float* in = d.inputs.data() + k * kDriverInputDim;
    float* pts = d.points.data() + k * d.point_len * 2;
    pts[0] = 0.f;
    pts[1] = -0.3f;
    for (int i = 0; i < kDriverSteps; ++i) {
      const State& s = r.car[i];
      in[4 * i] = float(s[0]);
      in[4 * i + 1] = float(s[1]);
      in[4 * i + 2] = float(s[2] - kHalfPi);
      in[4 * i + 3] = float(s[3]);
      pts[2 * (i + 1)] = float(s[0]);
      pts[2 * (i + 1) + 1] = float(s[1]);
    }
    for (int f = 0; f < 4; ++f) d.features_raw[k * 4 + f] = float(r.features[f]);
  }
  normalise_features(d);
  return d;
}

}  // namespace sirl
