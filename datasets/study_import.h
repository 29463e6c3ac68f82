// Answers collected elsewhere (another interface, a spreadsheet) → a Study, in the order given.
// One record per answered query, CSV or JSON:
//
//   CSV header: participant,kind,t1,t2,t3,answer,response_ms,timestamp,scenario,scenario_features
//   JSON:       {"answers": [{"participant": "p1", "kind": "similarity", "trajectories": [4, 9, 2],
//                "answer": 0, "response_ms": 2300, "timestamp": 1700000000.5,
//                "scenario": "...", "scenario_features": ["table", "laptop"]}, ...]}
//
// kind similarity: three rows of Ξ, answer = position (0, 1, 2) of the odd one out;
// kind preference: two rows, answer 1 = first preferred, 0 = second, 0.5 = equal.
// scenario / scenario_features (CSV: ';'-separated) are taken from a participant's first record.
#pragma once
#include <string>

#include "datasets/dataset.h"
#include "datasets/study.h"

namespace sirl {

// `into` gives env, trajectories and data seed; participants are appended. Throws
// std::invalid_argument "FILE:LINE: what" (CSV) or "FILE: record K: what" (JSON).
void import_study_csv(const std::string& path, const Dataset& d, Study& into);
void import_study_json(const std::string& path, const Dataset& d, Study& into);

}  // namespace sirl
