// The query bundle: every random stream it draws from has its own name.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "datasets/grid_robot.h"
#include "datasets/queries.h"
#include "datasets/query_bundle.h"
#include "kernels/rng.h"

namespace sirl {
namespace {

// The bundle lists every random stream it drew from (reward sets and query sets). One stream
// feeding two things correlates them (a MultiPref human's weights and its first queries were
// once drawn from one stream), so every name must be distinct, and each set must have one.
TEST(QueryBundle, EveryRandomStreamHasItsOwnName) {
  const Dataset d = make_grid_dataset();
  QueryBundleConfig c;
  c.similarity = 50;
  c.preference = 100;
  c.tpa_pairs = 20;
  c.fpe_trajectories = 100;
  const QueryBundle b = make_query_bundle(d, c, 3);
  const std::set<std::string> names(b.streams.begin(), b.streams.end());
  EXPECT_EQ(names.size(), b.streams.size()) << "a stream name is used twice";
  // 3 random reward sets, the similarity set, 3 preference sets, 20 TPA sets, the FPE split.
  EXPECT_EQ(b.streams.size(), size_t(3 + 1 + 3 + b.rewards.test.count + 1));
  for (const char* set : {"test", "multipref10", "multipref50"})
    EXPECT_TRUE(names.count(std::string("rewards/") + set)) << set;
  for (const char* set : {"similarity", "singlepref", "multipref10", "multipref50", "fpe"})
    EXPECT_TRUE(names.count(std::string("queries/") + set)) << set;
  // And the sets really are independent draws: the MultiPref-10 humans' weights are not the
  // normals of the stream that picks their queries.
  Rng q = Rng(seed_from_key("queries/multipref10", 3));
  const RewardSet from_query_stream = make_random_rewards("multipref10", 10, 4, q);
  EXPECT_NE(from_query_stream.weights, b.rewards.multipref10.weights);
}

}  // namespace
}  // namespace sirl
