// Reward sets and query sampling (paper §4.2): all draws uniform over Ξ from the caller's Rng,
// whose seed derives from the task key.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/dataset.h"
#include "datasets/simulated_human.h"
#include "datasets/streams.h"

namespace sirl {

struct RewardSet {
  std::string name;
  int count = 0, dim = 0;
  std::vector<float> weights;  // [count, dim], each row unit-norm
};

// Unit-norm directions w = g/‖g‖, g ~ N(0, I) (weights of either sign: a human may want a
// feature high or low), drawn from `rng`.
RewardSet make_random_rewards(const std::string& name, int count, int dim, Rng& rng);
// The same from the stream seed_from_key("rewards/" + name, seed).
RewardSet make_random_rewards(const std::string& name, int count, int dim, uint64_t seed);

// How many test rewards TPA averages over (the paper's 20), and the share of a TPA reward's pairs
// (and of FPE's trajectories) that train, the rest held out.
inline constexpr int kTestRewards = 20;
inline constexpr double kTrainFraction = 0.8;
// The training pairs of a TPA set of `total` pairs: round(kTrainFraction · total).
int64_t tpa_train_count(int64_t total);

// The paper's reward sets: 20 test rewards, 10 and 50 MultiPref training humans, and
// SinglePref's equal weights 1/√dim. Each random set from its own stream "rewards/<name>" of
// `streams` (never a stream the queries use); the sets are checked disjoint (no weight vector
// appears twice).
struct RewardSets {
  RewardSet test, multipref10, multipref50, singlepref;
};
RewardSets make_reward_sets(int dim, StreamSet& streams);
RewardSets make_reward_sets(int dim, uint64_t seed);

// N similarity triplets [N, 3] as (positive 1, positive 2, negative) row indices of Ξ.
struct TripletSet {
  std::vector<int32_t> idx;
  int64_t count = 0, skipped = 0;  // skipped: queries the teacher withheld (re-drawn)
};
// `rng` draws the queries; the teacher's own randomness (noise) draws from `answers`, or from
// `rng` when it is null. With a separate answer stream, teachers that differ only in their
// noise are asked the very same queries (a paired comparison); a perfect teacher draws nothing.
TripletSet sample_similarity_queries(const Dataset& d, int64_t N, const Teacher& t, Rng& rng,
                                     Rng* answers = nullptr);

// N preference pairs [N, 2] (A, B) with labels [N] (1 = A preferred, 0.5 = equal) and the human
// (row of `rewards`) who answered each. The N queries are split evenly over the K humans:
// human k answers N/K of them (the first N mod K humans one more), in blocks by human.
struct PreferenceSet {
  std::vector<int32_t> pairs;
  std::vector<float> label;
  std::vector<int32_t> human;
  int64_t count = 0, skipped = 0;
};
PreferenceSet sample_preference_queries(const Dataset& d, int64_t N, const RewardSet& rewards,
                                        const Teacher& t, Rng& rng, Rng* answers = nullptr);

// The first N triplets of a set (a method trained with N queries uses these, so the query sets
// of smaller N are nested in larger ones). Throws std::invalid_argument if N > s.count.
TripletSet first_triplets(const TripletSet& s, int64_t N);
// N queries of a set answered by K humans in blocks: human k keeps the first N/K of its block
// (the first N mod K humans one more), so each human keeps its share. Throws if a block is short.
PreferenceSet take_per_human(const PreferenceSet& s, int64_t N, int K);

// One reward's labelled pairs for TPA: the first `train` rows train the head (M ≤ train), the
// rest are held out (80/20 by default). The teacher answers the training pairs; the held-out
// pairs are labelled by the true reward (a perfect oracle on every feature), so accuracy is
// always measured against the truth. A held-out pair never repeats a training pair of its
// reward, in either order (it is drawn again from the same stream): TPA scores generalisation.
// kTpaHeldOutRule names that rule in the settings of every task that reads these sets.
inline constexpr const char* kTpaHeldOutRule = "tpa held_out=distinct_from_training\n";
struct TpaSet {
  PreferenceSet pairs;
  int64_t train = 0;
};
TpaSet sample_tpa_set(const Dataset& d, int64_t total, const RewardSet& rewards, int reward_row,
                      const Teacher& t, Rng& rng, double train_fraction = kTrainFraction,
                      Rng* answers = nullptr);

// FPE's labelled trajectories: `total` distinct rows of Ξ, shuffled; the first 80 % train the
// probe.
struct FpeSplit {
  std::vector<int32_t> train, test;
};
FpeSplit sample_fpe_split(const Dataset& d, int64_t total, Rng& rng,
                          double train_fraction = kTrainFraction);

}  // namespace sirl
