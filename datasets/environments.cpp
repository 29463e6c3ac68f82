#include "datasets/environments.h"

#include <stdexcept>

#include "datasets/grid_robot.h"

namespace sirl {

namespace {
Dataset grid(const JacoConfig&) {
  return make_grid_dataset();
}
Dataset grid2(const JacoConfig&) {
  return make_grid2_dataset();
}
Dataset jaco_with(const JacoConfig& j, bool human) {
  JacoConfig c = j;
  c.with_human = human;
  return make_jaco_dataset(c);
}
Dataset jaco(const JacoConfig& j) {
  return jaco_with(j, true);
}
Dataset jaco2(const JacoConfig& j) {
  return jaco_with(j, false);
}
int64_t grid_count(const JacoConfig&) {
  return kGridTrajectories;
}
int grid_dim(const JacoConfig&) {
  return kGridInputDim;
}
int64_t jaco_count(const JacoConfig& j) {
  return j.trajectories;
}
int jaco_dim(const JacoConfig& j) {
  return j.waypoints * kJacoStateDim;
}
}  // namespace

const std::vector<EnvSpec>& environments() {
  static const std::vector<EnvSpec> all{
      {"grid", "GridRobot", "5x5 grid, two obstacles and a laptop; 4 features", "grid", false, grid,
       grid_count, grid_dim},
      {"grid2", "GridRobot (laptop + angle)",
       "the paper's simplified GridRobot for Fig. 3: only the laptop and the joint angle", "grid",
       false, grid2, grid_count, grid_dim},
      {"jaco", "JacoRobot", "7-DoF Jaco arm with table, laptop and human; 4 features", "jaco", true,
       jaco, jaco_count, jaco_dim},
      {"jaco2", "JacoRobot (table + laptop)",
       "the user study's JacoRobot: no human; table and laptop features", "jaco", true, jaco2,
       jaco_count, jaco_dim},
  };
  return all;
}

std::string env_names() {
  std::string s;
  for (const auto& e : environments()) s += (s.empty() ? "" : ", ") + std::string(e.name);
  return s;
}

const EnvSpec& env_spec(const std::string& name) {
  for (const auto& e : environments())
    if (name == e.name) return e;
  throw std::invalid_argument("unknown environment '" + name + "' (expected one of " + env_names() +
                              ")");
}

}  // namespace sirl
