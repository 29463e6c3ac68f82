#include "datasets/query_bundle.h"

#include <algorithm>
#include <string>

namespace sirl {

QueryBundle make_query_bundle(const Dataset& d, const QueryBundleConfig& cfg, uint64_t seed) {
  QueryBundle b;
  b.config = cfg;
  b.seed = seed;
  StreamSet streams(seed);
  b.rewards = make_reward_sets(d.feature_count(), streams);
  auto stream = [&](const std::string& name) { return streams.open("queries/" + name); };
  Rng sim = stream("similarity");
  b.similarity = sample_similarity_queries(d, cfg.similarity, cfg.teacher, sim);
  Rng sp = stream("singlepref"), m10 = stream("multipref10"), m50 = stream("multipref50");
  b.singlepref =
      sample_preference_queries(d, cfg.preference, b.rewards.singlepref, cfg.teacher, sp);
  b.multipref10 =
      sample_preference_queries(d, cfg.preference, b.rewards.multipref10, cfg.teacher, m10);
  b.multipref50 =
      sample_preference_queries(d, cfg.preference, b.rewards.multipref50, cfg.teacher, m50);
  for (int r = 0; r < b.rewards.test.count; ++r) {
    Rng tr = stream("tpa/" + std::to_string(r));
    b.tpa.push_back(sample_tpa_set(d, cfg.tpa_pairs, b.rewards.test, r, cfg.teacher, tr));
  }
  Rng fr = stream("fpe");
  b.fpe = sample_fpe_split(d, std::min<int64_t>(cfg.fpe_trajectories, d.count), fr);
  b.streams = streams.opened();
  return b;
}

}  // namespace sirl
