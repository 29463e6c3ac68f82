// The study file (HDF5): participants, their queries and every answer with its response time
// and timestamp. Rewritten atomically (temporary file, fsync, rename) on every change, so a
// crash at any moment leaves the previous complete version:
//   /study                         attrs format = "sirl-study-1", env, trajectories, data_seed
//   /study/participant_ids         [P] strings, in creation order
//   /study/participants/<id>/      attrs token, scenario, scenario_features
//       similarity [n,3] int32, preference [m,2] int32 (rows of Ξ), reward [F] (simulated only)
//       similarity_answer [k] int32 (odd one out: 0, 1, 2), preference_answer [k] float32
//       (1 = first preferred, 0 = second, 0.5 = equal), *_ms [k] float32, *_time [k] float64
#pragma once
#include <string>

#include "datasets/study.h"

namespace sirl {

void write_study(const std::string& path, const Study& s);
// Throws H5Error naming the file and object when something is missing or malformed.
Study read_study(const std::string& path);

}  // namespace sirl
