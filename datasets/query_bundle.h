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
};

// Each reward set and each query set draws from its own named stream of `seed` ("rewards/test",
// "queries/similarity", "queries/tpa/3", …; listed in `streams`), so adding a set never changes
// the others and no two sets share draws.
QueryBundle make_query_bundle(const Dataset& d, const QueryBundleConfig& cfg, uint64_t seed);

}  // namespace sirl
