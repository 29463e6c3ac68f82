#include "datasets/query_bundle.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace sirl {

namespace {

// The features a teacher of `attend` < 1 perceives: k = max(1, round(attend·F)) of F, uniformly.
std::vector<uint8_t> draw_mask(int F, double attend, Rng& rng) {
  if (!(attend > 0 && attend <= 1))
    throw std::invalid_argument("teacher attend must be in (0, 1], the share of features seen");
  const int k = std::max(1, int(std::lround(attend * F)));
  std::vector<int> order(F);
  std::iota(order.begin(), order.end(), 0);
  for (int i = 0; i < k; ++i) std::swap(order[i], order[i + int(rng.uniform_int(F - i))]);
  std::vector<uint8_t> mask(F, 0);
  for (int i = 0; i < k; ++i) mask[order[i]] = 1;
  return mask;
}

double sqdist(const float* a, const float* b, int F) {
  double s = 0;
  for (int f = 0; f < F; ++f) s += double(a[f] - b[f]) * (a[f] - b[f]);
  return s;
}

// Share of triplets (p1, p2, neg) whose pair (p1, p2) is not the closest of the three on every
// feature (ties count as agreement).
double similarity_error(const Dataset& d, const TripletSet& s) {
  if (s.count == 0) return 0;
  const int F = d.feature_count();
  int64_t wrong = 0;
  for (int64_t i = 0; i < s.count; ++i) {
    const float *a = d.feature(s.idx[3 * i]), *b = d.feature(s.idx[3 * i + 1]),
                *n = d.feature(s.idx[3 * i + 2]);
    const double pair = sqdist(a, b, F);
    wrong += pair > sqdist(a, n, F) || pair > sqdist(b, n, F);
  }
  return double(wrong) / double(s.count);
}

// Labels that disagree with the true reward's sign, counted over the first `n` pairs of `s`
// (human k answered with row s.human[k] of `r`; exact ties agree with any label).
void count_preference_errors(const Dataset& d, const PreferenceSet& s, const RewardSet& r,
                             int64_t n, int64_t& wrong, int64_t& total) {
  const int F = d.feature_count();
  for (int64_t i = 0; i < n; ++i) {
    const float* w = r.weights.data() + size_t(s.human[i]) * r.dim;
    const double diff =
        reward(w, d.feature(s.pairs[2 * i]), F) - reward(w, d.feature(s.pairs[2 * i + 1]), F);
    const float truth = diff > 0 ? 1.f : 0.f;
    wrong += diff != 0 && s.label[i] != truth;
    ++total;
  }
}

}  // namespace

QueryBundle make_query_bundle(const Dataset& d, const QueryBundleConfig& cfg, uint64_t seed) {
  QueryBundle b;
  b.config = cfg;
  b.seed = seed;
  StreamSet streams(seed);
  b.rewards = make_reward_sets(d.feature_count(), streams);
  if (cfg.attend != 1.0) {
    Rng mr = streams.open("teacher/mask");
    b.config.teacher.mask = draw_mask(d.feature_count(), cfg.attend, mr);
  }
  const Teacher& teacher = b.config.teacher;
  // The paper's teacher draws nothing; a noisy one draws its answers from streams of its own
  // (not opened for the perfect teacher, whose bundle stays what it always was).
  const bool noisy = !teacher.perfect();
  auto stream = [&](const std::string& name) { return streams.open("queries/" + name); };
  auto answers = [&](const std::string& name) {
    return noisy ? streams.open("answers/" + name) : Rng(0);
  };
  Rng sim = stream("similarity"), sim_a = answers("similarity");
  b.similarity =
      sample_similarity_queries(d, cfg.similarity, teacher, sim, noisy ? &sim_a : nullptr);
  Rng sp = stream("singlepref"), m10 = stream("multipref10"), m50 = stream("multipref50");
  Rng sp_a = answers("singlepref"), m10_a = answers("multipref10"), m50_a = answers("multipref50");
  b.singlepref = sample_preference_queries(d, cfg.preference, b.rewards.singlepref, teacher, sp,
                                           noisy ? &sp_a : nullptr);
  b.multipref10 = sample_preference_queries(d, cfg.preference, b.rewards.multipref10, teacher, m10,
                                            noisy ? &m10_a : nullptr);
  b.multipref50 = sample_preference_queries(d, cfg.preference, b.rewards.multipref50, teacher, m50,
                                            noisy ? &m50_a : nullptr);
  for (int r = 0; r < b.rewards.test.count; ++r) {
    Rng tr = stream("tpa/" + std::to_string(r)), tr_a = answers("tpa/" + std::to_string(r));
    b.tpa.push_back(sample_tpa_set(d, cfg.tpa_pairs, b.rewards.test, r, teacher, tr, kTrainFraction,
                                   noisy ? &tr_a : nullptr));
  }
  Rng fr = stream("fpe");
  b.fpe = sample_fpe_split(d, std::min<int64_t>(cfg.fpe_trajectories, d.count), fr);
  b.streams = streams.opened();

  b.answer_error.similarity = similarity_error(d, b.similarity);
  int64_t wrong = 0, total = 0;
  count_preference_errors(d, b.singlepref, b.rewards.singlepref, b.singlepref.count, wrong, total);
  count_preference_errors(d, b.multipref10, b.rewards.multipref10, b.multipref10.count, wrong,
                          total);
  count_preference_errors(d, b.multipref50, b.rewards.multipref50, b.multipref50.count, wrong,
                          total);
  for (const TpaSet& t : b.tpa)
    count_preference_errors(d, t.pairs, b.rewards.test, t.train, wrong, total);
  b.answer_error.preference = total ? double(wrong) / double(total) : 0.0;
  return b;
}

}  // namespace sirl
