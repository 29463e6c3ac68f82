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
  MethodConfig m{Method::sirl, b.similarity.count, false, c.hyper};
  return train_representation(d, b, m, seed, nullptr, Execution{c.threads});
}

Representation random_phi(const Dataset& d, const StudyAnalysisConfig& c, uint64_t seed) {
  QueryBundle b;
  return train_representation(d, b, MethodConfig{Method::random, 0, false, c.hyper}, seed, nullptr,
                              Execution{c.threads});
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
    return evaluate_tpa(rep, d, sets, TpaConfig{M, true, c.hyper}, seed, Execution{c.threads})
        .accuracy;
  std::vector<double> acc;
  for (size_t k = 0; k < sets.size(); k += kUnfrozenChunk) {
    const std::vector<TpaSet> chunk(sets.begin() + k,
                                    sets.begin() + std::min(sets.size(), k + kUnfrozenChunk));
    const TpaResult r = evaluate_tpa(rep, d, chunk, TpaConfig{M, false, c.hyper},
                                     seed_from_key("unfrozen_chunk/" + std::to_string(k), seed),
                                     Execution{c.threads});
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

std::vector<int32_t> study_triplets(const Study& s, const std::string& without) {
  std::vector<const StudyParticipant*> who;
  for (const auto& p : s.participants)
    if (p.id != without) who.push_back(&p);
  return answered_triplets(who);
}

Representation study_sirl(const Dataset& d, const std::vector<int32_t>& triplets,
                          const StudyAnalysisConfig& c, int k) {
  return train_sirl_on(d, triplets, c, seed_from_key("study_seed/" + std::to_string(k), c.seed));
}

Representation study_random(const Dataset& d, const StudyAnalysisConfig& c, int k) {
  return random_phi(d, c, seed_from_key("study_seed/" + std::to_string(k), c.seed));
}

double study_fpe(const Representation& phi, const Dataset& d, const StudyAnalysisConfig& c) {
  // One fixed labelled split for every φ of the analysis.
  Rng fpe_rng(seed_from_key("study_fpe", c.seed));
  const FpeSplit split = sample_fpe_split(d, std::min(c.fpe_trajectories, d.count), fpe_rng);
  return evaluate_fpe(phi, d, split, c.threads).fpe;
}

Representation study_heldout(const Study& s, const Dataset& d, const std::string& id,
                             const StudyAnalysisConfig& c) {
  const auto trip = study_triplets(s, id);
  if (trip.empty()) return Representation{};
  return train_sirl_on(d, trip, c, seed_from_key("study_heldout", c.seed));
}

bool study_participant_usable(const StudyParticipant& p, const StudyAnalysisConfig& c) {
  int64_t M = 0;
  StudyAnalysisConfig one = c;
  one.cv_splits = 1;
  return !cv_sets(p, one, c.seed, &M).empty();
}

ParticipantTpa study_participant_tpa(const StudyParticipant& p, const Dataset& d,
                                     const Representation& sirl0, const Representation& random0,
                                     const Representation& heldout, const StudyAnalysisConfig& c) {
  ParticipantTpa t;
  int64_t M = 0;
  const auto sets = cv_sets(p, c, c.seed, &M);
  if (sets.empty()) return t;
  const uint64_t tpa_seed = seed_from_key("study_tpa", c.seed);
  t.ok = true;
  t.both_features = p.scenario_features.size() >= size_t(d.feature_count());
  t.real_sirl = tpa_mean(sirl0, d, sets, M, c, tpa_seed);
  t.real_random = tpa_mean(random0, d, sets, M, c, tpa_seed, c.random_frozen);
  t.real_random_other = tpa_mean(random0, d, sets, M, c, tpa_seed, !c.random_frozen);
  t.heldout_sirl = heldout.params.empty() ? NAN : tpa_mean(heldout, d, sets, M, c, tpa_seed);
  return t;
}

SimulatedTpa study_simulated_tpa(const Dataset& d, const Representation& sirl0,
                                 const Representation& random0, const StudyAnalysisConfig& c) {
  const uint64_t tpa_seed = seed_from_key("study_tpa", c.seed);
  const RewardSet rewards =
      make_random_rewards("study_simulated", c.simulated_rewards, d.feature_count(), c.seed);
  std::vector<TpaSet> sim;
  Rng sim_rng(seed_from_key("study_simulated_queries", c.seed));
  for (int r = 0; r < rewards.count; ++r)
    sim.push_back(
        sample_tpa_set(d, c.simulated_queries, rewards, r, Teacher{}, sim_rng, c.train_fraction));
  const int64_t M = sim.front().train;
  SimulatedTpa t;
  t.sirl = evaluate_tpa(sirl0, d, sim, TpaConfig{M, true, c.hyper}, tpa_seed, Execution{c.threads})
               .accuracy;
  t.random = tpa_accuracies(random0, d, sim, M, c, tpa_seed, c.random_frozen);
  t.random_other = tpa_accuracies(random0, d, sim, M, c, tpa_seed, !c.random_frozen);
  return t;
}

StudyAnalysis analyze_study(const Study& s, const Dataset& d, const StudyAnalysisConfig& c) {
  StudyAnalysis a;
  const std::vector<int32_t> pooled = study_triplets(s);
  a.triplets = int64_t(pooled.size() / 3);
  if (a.triplets == 0) throw std::invalid_argument("the study has no similarity answers yet");
  std::vector<Representation> sirl, random;
  for (int k = 0; k < c.seeds; ++k) {
    sirl.push_back(study_sirl(d, pooled, c, k));
    random.push_back(study_random(d, c, k));
    a.fpe_sirl.push_back(study_fpe(sirl.back(), d, c));
    a.fpe_random.push_back(study_fpe(random.back(), d, c));
  }
  for (const auto& p : s.participants) {
    if (!study_participant_usable(p, c)) continue;
    const ParticipantTpa t =
        study_participant_tpa(p, d, sirl[0], random[0], study_heldout(s, d, p.id, c), c);
    add_participant(a, p.id, t);
    if (c.progress) c.progress(int(a.participants.size()), int(s.participants.size()));
  }
  set_simulated(a, study_simulated_tpa(d, sirl[0], random[0], c));
  return a;
}

void add_participant(StudyAnalysis& a, const std::string& id, const ParticipantTpa& t) {
  if (!t.ok) return;
  a.participants.push_back(id);
  a.both_features.push_back(t.both_features);
  a.real_sirl.push_back(t.real_sirl);
  a.real_random.push_back(t.real_random);
  a.real_random_other.push_back(t.real_random_other);
  a.heldout_sirl.push_back(t.heldout_sirl);
  a.heldout_random.push_back(t.real_random);  // Random uses nobody's data
  a.heldout_random_other.push_back(t.real_random_other);
}

void set_simulated(StudyAnalysis& a, const SimulatedTpa& t) {
  a.simulated_sirl = t.sirl;
  a.simulated_random = t.random;
  a.simulated_random_other = t.random_other;
}

}  // namespace sirl
