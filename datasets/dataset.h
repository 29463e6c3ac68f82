// What every environment produces (MuJoCo's mjModel in spirit: built once, then read-only):
// the enumerated or sampled trajectory space Ξ as network inputs, and the true features φ*.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace sirl {

struct Dataset {
  std::string env;                // "grid" or "jaco"
  int input_dim = 0;              // floats per trajectory (grid 19, jaco 2037)
  int64_t count = 0;              // T, trajectories in Ξ
  std::vector<float> inputs;      // [T, input_dim] what the networks see
  std::string input_description;  // layout and scaling of one input row
  std::vector<std::string> feature_names;
  std::vector<std::string> feature_units;       // [F] units of features_raw
  std::vector<float> features_raw;              // [T, F] φ* in physical units
  std::vector<float> features;                  // [T, F] φ* min-max normalised over Ξ to [0, 1]
  std::vector<float> feature_min, feature_max;  // [F] the normalisation
  std::vector<std::string> object_names;
  std::vector<float> object_positions;  // [objects, 2 or 3]
  int object_dim = 0;
  std::string object_units;  // e.g. "cells" or "m"
  uint64_t seed = 0;         // generator seed (0 for an exact enumeration)
  // Sampled environments keep the configuration-space paths behind the inputs (JacoRobot:
  // paths [T, path_len, path_dofs] joint angles in rad) and the model they came from.
  std::vector<float> paths;
  int path_len = 0, path_dofs = 0;
  std::string model_text;
  // What a figure draws of each trajectory, for an environment read from a file: points
  // [T, point_len, point_dim] (point_dim 2 or 3), in the file's units; empty if none.
  std::vector<float> points;
  int point_len = 0, point_dim = 0;

  int feature_count() const { return int(feature_names.size()); }
  const float* input(int64_t i) const { return inputs.data() + i * input_dim; }
  const float* feature(int64_t i) const { return features.data() + i * feature_count(); }
};

// Fills `features`, `feature_min` and `feature_max` from `features_raw`: (φ − min)/(max − min)
// per feature over Ξ; a feature constant over Ξ maps to 0.
void normalise_features(Dataset& d);

}  // namespace sirl
