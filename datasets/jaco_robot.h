// JacoRobot (paper §4.1, Appendix A; docs/ARCHITECTURE.md §3): a 7-DoF Kinova Jaco (j2s7s300) over
// a table with a laptop and a human. Trajectories are straight joint-space paths between random
// start and goal configurations, smoothly deformed (ξ_D = ξ + μ A⁻¹ ũ, A the acceleration norm,
// factored once with CHOLMOD); forward kinematics runs through MuJoCo 2.2 (`mj_kinematics`).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/dataset.h"

namespace sirl {

struct JacoConfig {
  int64_t trajectories = 10000;  // start–goal pairs, one trajectory each
  int waypoints = 21;            // H + 1 states per trajectory
  int max_deformations = 3;      // each trajectory gets 1..max random deformations
  double max_deformation = 0.5;  // rad: the largest joint displacement one deformation makes
  std::array<double, 3> laptop{0.0, -0.8, 0.0};  // lineage positions, robot base frame (m)
  std::array<double, 3> human{-0.2, -0.5, 0.6};
  double table_z = 0.0;    // table top height (the base stands on it)
  bool with_human = true;  // false: the user-study variant "jaco2" (no human; table + laptop)
  uint64_t seed = 0;
  int threads = 0;  // 0 = every core (the result never depends on it)
};

// Throws std::invalid_argument naming the bad field.
void validate(const JacoConfig& cfg);

// Floats per state (7 angles, 7 rotation matrices, 7 frame positions, laptop xyz, human xyz),
// and where each part starts within a state.
constexpr int kJacoStateDim = 97;
constexpr int kJacoDofs = 7;
constexpr int kJacoAngles = 0;                                  // [7] joint angles, rad
constexpr int kJacoRotations = kJacoAngles + kJacoDofs;         // [7, 9] row-major, world frame
constexpr int kJacoPositions = kJacoRotations + 9 * kJacoDofs;  // [7, 3] m, world frame
constexpr int kJacoEndEffector = kJacoPositions + 3 * (kJacoDofs - 1);  // frame 7's [3]
constexpr int kJacoLaptop = kJacoPositions + 3 * kJacoDofs;             // [3] m
constexpr int kJacoHuman = kJacoLaptop + 3;                             // [3] m (zeros in jaco2)
static_assert(kJacoHuman + 3 == kJacoStateDim);

// env "jaco" (4 features: table, upright, laptop, proxemics) or "jaco2" (table, laptop).
// inputs [T, waypoints·97]; joint_paths [T, waypoints, 7] are kept in Dataset::paths.
Dataset make_jaco_dataset(const JacoConfig& cfg = {});

// The MJCF text of the arm and scene (datasets/jaco_j2s7s300.xml, compiled in).
const char* jaco_model_xml();

// Forward kinematics of one configuration: DH frames 1..7 (7 = end effector) as positions
// [7, 3] and row-major rotation matrices [7, 9] in the world frame, through MuJoCo.
struct JacoFrames {
  std::array<double, 21> pos;
  std::array<double, 63> rot;
};
class JacoKinematics {
 public:
  explicit JacoKinematics(const JacoConfig& cfg = {});
  ~JacoKinematics();
  JacoKinematics(const JacoKinematics&) = delete;
  JacoKinematics& operator=(const JacoKinematics&) = delete;
  // Thread-safe when each thread passes its own workspace index in [0, workspaces()).
  JacoFrames frames(const double* q, int workspace = 0) const;
  int workspaces() const;
  void ensure_workspaces(int n);
  // Joint limits: lower/upper (±π for continuous joints), and which joints are limited.
  std::array<double, 7> lower, upper;
  std::array<bool, 7> limited;

 private:
  struct Impl;
  Impl* impl_;
};

// The true features of one state from its end-effector frame (see docs/ARCHITECTURE.md §3).
//   table      EE height above the table (m)
//   upright    1 − (EE x-axis · world z)
//   laptop     max(0, 0.3 − ‖EE_xy − laptop_xy‖)
//   proxemics  max(0, 0.3 − ‖(Δx, Δy/3)‖) toward the human
std::array<double, 4> jaco_state_features(const JacoConfig& cfg, const double* ee_pos,
                                          const double* ee_rot);

// MuJoCo's version at run time, for provenance.
std::string mujoco_version();
}  // namespace sirl
