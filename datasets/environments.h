// The environments, declared once each (name, what it is, how to build its Ξ, its sizes, whose
// paper hyper-parameters it uses); code that needs an environment looks it up here instead of
// comparing names.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/dataset.h"
#include "datasets/jaco_robot.h"

namespace sirl {

struct EnvSpec {
  const char* name;         // "grid", "grid2", "jaco", "jaco2"
  const char* title;        // for figures: "GridRobot", …
  const char* description;  // one line
  const char* family;       // "grid" or "jaco": the paper's hyper-parameters it uses
  bool sampled;             // Ξ sampled from the JacoConfig (trajectories, seed) or enumerated
  // Ξ for this environment. JacoRobot variants read `jaco` (trajectories, seed, objects).
  Dataset (*make)(const JacoConfig& jaco);
  int64_t (*trajectories)(const JacoConfig& jaco);  // |Ξ| without building it
  int (*input_dim)(const JacoConfig& jaco);         // floats per trajectory
};

const std::vector<EnvSpec>& environments();
// Throws std::invalid_argument naming the known environments.
const EnvSpec& env_spec(const std::string& name);
// "grid, grid2, jaco, jaco2".
std::string env_names();

}  // namespace sirl
