// An environment read from a file (docs/environment-files.md): a user's own trajectories and
// true features, declared by a profile as [environments.<name>] and run by every method, metric
// and figure as the built-in environments are. The layout is the one `sirl dataset` exports, so
// an exported built-in environment reads back as a file environment:
//   /datasets/<group>/inputs        [T, D] float32 (or float64): what the networks see
//   /datasets/<group>/features_raw  [T, F] float32 (or float64): the true features, any units;
//                                   @feature_names [F] strings, @units [F] strings (optional)
//   /datasets/<group>/points        [T, L, 2|3] (optional): what a figure draws of each trajectory
// The file is untrusted input: its digest must be the one the profile names, it is read in a
// forked child first, every shape is checked before anything is allocated, and the values must
// be finite with no constant feature (the simulated humans could not tell trajectories apart by
// it). Any problem is one std::invalid_argument naming the file.
#pragma once
#include <cstdint>
#include <string>

#include "datasets/dataset.h"

namespace sirl {

// Limits of a file environment: far above any robot-learning trajectory set, low enough that a
// crafted shape cannot ask for more memory than a node has before its values are read.
inline constexpr uint64_t kMaxFileTrajectories = 10'000'000;
inline constexpr uint64_t kMaxFileInputDim = 1'000'000;
inline constexpr uint64_t kMaxFileValues = uint64_t(1) << 31;  // T·D (8 GiB of float32)
inline constexpr uint64_t kMaxFileFeatures = 256;
inline constexpr uint64_t kMaxFilePointsPerTrajectory = 10'000;
inline constexpr int64_t kMinFileTrajectories = 3;  // a similarity query needs three

struct EnvironmentFileSpec {
  std::string env;    // the environment's name in the profile (Dataset::env)
  std::string path;   // the file
  std::string xxh3;   // its XXH3-128 as the profile names it (32 lowercase hex digits)
  std::string group;  // /datasets/<group> (default: env)
};

// The file's Ξ as a Dataset: inputs, features_raw, features normalised over Ξ as the built-in
// environments' are (normalise_features), feature names and units, and the points if the file
// has them.
Dataset read_environment_file(const EnvironmentFileSpec& spec);

}  // namespace sirl
