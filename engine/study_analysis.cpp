#include "engine/study_analysis.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "datasets/queries.h"
#include "datasets/query_bundle.h"
#include "engine/fpe.h"
#include "engine/methods.h"
#include "engine/tpa.h"

namespace sirl {

namespace {

Representation train_sirl_on(const Dataset& d, const std::vector<int32_t>& triplets,
                             const StudyAnalysisConfig& c, uint64_t seed) {
  QueryBundle b;
  b.similarity.idx = triplets;
  b.similarity.count = int64_t(triplets.size() / 3);
  MethodConfig m{Method::sirl, b.similarity.count, false, c.hyper, c.threads};
  return train_representation(d, b, m, seed);
}

Representation random_phi(const Dataset& d, const StudyAnalysisConfig& c, uint64_t seed) {
  QueryBundle b;
  return train_representation(d, b, MethodConfig{Method::random, 0, false, c.hyper, c.threads},
                              seed);
}

// `splits` random 70/30 partitions of one participant's answered, non-tied preferences.
std::vector<TpaSet> cv_sets(const StudyParticipant& p, const StudyAnalysisConfig& c, uint64_t seed,
                            int64_t* train) {
  std::vector<int64_t> rows;
  for (int64_t i = 0; i < p.preference_done(); ++i)
    if (p.preference_answer[i] != 0.5f) rows.push_back(i);
  const int64_t n = int64_t(rows.size());
  *train = std::llround(c.train_fraction * double(n));
  if (n < 2 || *train < 1 || *train >= n) return {};
  std::vector<TpaSet> sets;
  Rng rng(seed_from_key("study_cv/" + p.id, seed));
  for (int k = 0; k < c.cv_splits; ++k) {
    std::vector<int64_t> order = rows;
    for (int64_t i = n - 1; i > 0; --i)
      std::swap(order[i], order[rng.uniform_int(uint64_t(i + 1))]);
    TpaSet s;
    for (int64_t j : order) {
      s.pairs.pairs.push_back(p.preference[2 * j]);
      s.pairs.pairs.push_back(p.preference[2 * j + 1]);
      s.pairs.label.push_back(p.preference_answer[j]);
      s.pairs.human.push_back(0);
    }
    s.pairs.count = n;
    s.train = *train;
    sets.push_back(std::move(s));
  }
  return sets;
}

// Per-set held-out accuracies. Unfrozen cells fine-tune one copy of φ per set: they run in
// chunks of kUnfrozenChunk sets so memory stays bounded (JacoRobot: 3.1 M weights, ×4 with the
// gradient and Adam's moments, per copy); each chunk's heads draw from their own stream.
constexpr size_t kUnfrozenChunk = 10;
std::vector<double> tpa_accuracies(const Representation& rep, const Dataset& d,
                                   const std::vector<TpaSet>& sets, int64_t M,
                                   const StudyAnalysisConfig& c, uint64_t seed, bool frozen) {
  if (frozen)
    return evaluate_tpa(rep, d, sets, TpaConfig{M, true, c.hyper, c.threads}, seed).accuracy;
  std::vector<double> acc;
  for (size_t k = 0; k < sets.size(); k += kUnfrozenChunk) {
    const std::vector<TpaSet> chunk(sets.begin() + k,
                                    sets.begin() + std::min(sets.size(), k + kUnfrozenChunk));
    const TpaResult r = evaluate_tpa(rep, d, chunk, TpaConfig{M, false, c.hyper, c.threads},
                                     seed_from_key("unfrozen_chunk/" + std::to_string(k), seed));
    acc.insert(acc.end(), r.accuracy.begin(), r.accuracy.end());
  }
  return acc;
}

double tpa_mean(const Representation& rep, const Dataset& d, const std::vector<TpaSet>& sets,
                int64_t M, const StudyAnalysisConfig& c, uint64_t seed, bool frozen = true) {
  const auto acc = tpa_accuracies(rep, d, sets, M, c, seed, frozen);
  return std::accumulate(acc.begin(), acc.end(), 0.0) / double(acc.size());
}

}  // namespace

StudyAnalysis analyze_study(const Study& s, const Dataset& d, const StudyAnalysisConfig& c) {
  StudyAnalysis a;
  std::vector<const StudyParticipant*> all;
  for (const auto& p : s.participants) all.push_back(&p);
  const std::vector<int32_t> pooled = answered_triplets(all);
  a.triplets = int64_t(pooled.size() / 3);
  if (a.triplets == 0) throw std::invalid_argument("the study has no similarity answers yet");

  // FPE: one fixed labelled split; SIRL and Random for each training seed.
  Rng fpe_rng(seed_from_key("study_fpe", c.seed));
  const FpeSplit split = sample_fpe_split(d, std::min(c.fpe_trajectories, d.count), fpe_rng);
  std::vector<Representation> sirl, random;
  for (int k = 0; k < c.seeds; ++k) {
    const uint64_t seed = seed_from_key("study_seed/" + std::to_string(k), c.seed);
    sirl.push_back(train_sirl_on(d, pooled, c, seed));
    random.push_back(random_phi(d, c, seed));
    a.fpe_sirl.push_back(evaluate_fpe(sirl.back(), d, split, c.threads).fpe);
    a.fpe_random.push_back(evaluate_fpe(random.back(), d, split, c.threads).fpe);
  }

  // TPA on each participant's own preferences: Real and Held-out.
  const uint64_t tpa_seed = seed_from_key("study_tpa", c.seed);
  for (const auto& p : s.participants) {
    int64_t M = 0;
    const auto sets = cv_sets(p, c, c.seed, &M);
    if (sets.empty()) continue;
    a.participants.push_back(p.id);
    a.both_features.push_back(p.scenario_features.size() >= size_t(d.feature_count()));
    a.real_sirl.push_back(tpa_mean(sirl[0], d, sets, M, c, tpa_seed));
    a.real_random.push_back(tpa_mean(random[0], d, sets, M, c, tpa_seed, c.random_frozen));
    a.real_random_other.push_back(tpa_mean(random[0], d, sets, M, c, tpa_seed, !c.random_frozen));
    std::vector<const StudyParticipant*> others;
    for (const auto& q : s.participants)
      if (q.id != p.id) others.push_back(&q);
    const auto trip = answered_triplets(others);
    if (trip.empty()) {
      a.heldout_sirl.push_back(NAN);
    } else {
      const Representation held = train_sirl_on(d, trip, c, seed_from_key("study_heldout", c.seed));
      a.heldout_sirl.push_back(tpa_mean(held, d, sets, M, c, tpa_seed));
    }
    a.heldout_random.push_back(a.real_random.back());  // Random uses nobody's data
    a.heldout_random_other.push_back(a.real_random_other.back());
    if (c.progress) c.progress(int(a.participants.size()), int(s.participants.size()));
  }

  // Simulated: perfect preferences for random rewards.
  const RewardSet rewards =
      make_random_rewards("study_simulated", c.simulated_rewards, d.feature_count(), c.seed);
  std::vector<TpaSet> sim;
  Rng sim_rng(seed_from_key("study_simulated_queries", c.seed));
  for (int r = 0; r < rewards.count; ++r)
    sim.push_back(
        sample_tpa_set(d, c.simulated_queries, rewards, r, Teacher{}, sim_rng, c.train_fraction));
  const int64_t Msim = sim.front().train;
  const TpaResult ts =
      evaluate_tpa(sirl[0], d, sim, TpaConfig{Msim, true, c.hyper, c.threads}, tpa_seed);
  a.simulated_sirl = ts.accuracy;
  a.simulated_random = tpa_accuracies(random[0], d, sim, Msim, c, tpa_seed, c.random_frozen);
  a.simulated_random_other = tpa_accuracies(random[0], d, sim, Msim, c, tpa_seed, !c.random_frozen);
  return a;
}

}  // namespace sirl
