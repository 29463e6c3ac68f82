// Everything a representation/metric task needs from one environment and one data seed: the
// reward sets and every query set, answered by one teacher. `sirl dataset` stores it whole.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/queries.h"

namespace sirl {

struct QueryBundleConfig {
  int64_t similarity = 1000;        // triplets (the largest N of the paper)
  int64_t preference = 1000;        // pairs for each of SinglePref, MultiPref-10, MultiPref-50
  int64_t tpa_pairs = 250;          // labelled pairs per test reward (80 % train ⇒ M up to 200)
  int64_t fpe_trajectories = 1000;  // labelled trajectories for FPE (clamped to |Ξ|)
  Teacher teacher;                  // default: the paper's perfect oracle
  // Share of the features the teacher perceives (1 = all). Below 1 the teacher attends to a
  // random subset of max(1, round(attend·F)) features, drawn per seed from "teacher/mask"; it
  // answers similarity and preference queries from those alone (teacher.mask).
  double attend = 1.0;
};

// How far a bundle's answers are from those of the perfect oracle on every feature: the share
// of similarity answers whose closest pair is not the truly closest, and of preference labels
// (SinglePref, MultiPref and the TPA training pairs) that disagree with the true reward's sign.
// 0 for the paper's teacher; a β = 0 teacher has 2/3 and about 1/2.
struct AnswerError {
  double similarity = 0, preference = 0;
};

struct QueryBundle {
  QueryBundleConfig config;
  uint64_t seed = 0;
  RewardSets rewards;
  TripletSet similarity;
  PreferenceSet singlepref, multipref10, multipref50;
  std::vector<TpaSet> tpa;  // one per test reward
  FpeSplit fpe;
  std::vector<std::string> streams;  // every random stream the bundle drew from, in order
  AnswerError answer_error;
};

// Each reward set and each query set draws from its own named stream of `seed` ("rewards/test",
// "queries/similarity", "queries/tpa/3", …; listed in `streams`), so adding a set never changes
// the others and no two sets share draws. A teacher with noise draws its answers from streams of
// their own ("answers/similarity", …), so every teacher is asked the same queries (unless it
// skips some). config.teacher.mask holds the drawn mask when attend < 1.
QueryBundle make_query_bundle(const Dataset& d, const QueryBundleConfig& cfg, uint64_t seed);

}  // namespace sirl
