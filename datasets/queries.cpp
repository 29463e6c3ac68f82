#include "datasets/queries.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <set>
#include <stdexcept>

namespace sirl {

RewardSet make_random_rewards(const std::string& name, int count, int dim, uint64_t seed) {
  Rng rng(seed_from_key("rewards/" + name, seed));
  return make_random_rewards(name, count, dim, rng);
}

RewardSet make_random_rewards(const std::string& name, int count, int dim, Rng& rng) {
  RewardSet r{name, count, dim, std::vector<float>(size_t(count) * dim)};
  for (int i = 0; i < count; ++i) {
    double norm = 0;
    std::vector<double> g(dim);
    do {
      norm = 0;
      for (auto& v : g) {
        v = rng.normal();
        norm += v * v;
      }
    } while (norm < 1e-12);
    for (int k = 0; k < dim; ++k) r.weights[size_t(i) * dim + k] = float(g[k] / std::sqrt(norm));
  }
  return r;
}

RewardSets make_reward_sets(int dim, uint64_t seed) {
  StreamSet streams(seed);
  return make_reward_sets(dim, streams);
}

RewardSets make_reward_sets(int dim, StreamSet& streams) {
  auto random = [&](const char* name, int count) {
    Rng rng = streams.open(std::string("rewards/") + name);
    return make_random_rewards(name, count, dim, rng);
  };
  RewardSets s{
      random("test", kTestRewards), random("multipref10", 10), random("multipref50", 50),
      RewardSet{"singlepref", 1, dim, std::vector<float>(dim, float(1 / std::sqrt(double(dim))))}};
  std::set<std::vector<float>> seen;
  for (const RewardSet* r : {&s.test, &s.multipref10, &s.multipref50, &s.singlepref})
    for (int i = 0; i < r->count; ++i)
      if (!seen.insert(std::vector<float>(r->weights.begin() + size_t(i) * dim,
                                          r->weights.begin() + size_t(i + 1) * dim))
               .second)
        throw std::logic_error("reward sets overlap: " + r->name + " row " + std::to_string(i));
  return s;
}

namespace {
void check_sample_size(const Dataset& d, int64_t n, int per_query, const char* what) {
  if (n < 0) throw std::invalid_argument(std::string(what) + ": negative query count");
  if (d.count < per_query)
    throw std::invalid_argument(std::string(what) + ": dataset has too few trajectories");
}
// A teacher who withholds almost every answer would loop forever; give up with a message.
void check_attempts(int64_t attempts, int64_t n, const char* what) {
  if (attempts > 1000 * (n + 10))
    throw std::runtime_error(
        std::string(what) +
        ": the teacher skipped more than 99.9% of queries; lower its skip threshold");
}
}  // namespace

TripletSet sample_similarity_queries(const Dataset& d, int64_t N, const Teacher& t, Rng& rng,
                                     Rng* answers) {
  check_sample_size(d, N, 3, "similarity queries");
  validate(t, d.feature_count());
  TripletSet s;
  s.idx.reserve(size_t(N) * 3);
  int64_t attempts = 0;
  while (s.count < N) {
    check_attempts(++attempts, N, "similarity queries");
    std::array<int32_t, 3> q;
    q[0] = int32_t(rng.uniform_int(d.count));
    do q[1] = int32_t(rng.uniform_int(d.count));
    while (q[1] == q[0]);
    do q[2] = int32_t(rng.uniform_int(d.count));
    while (q[2] == q[0] || q[2] == q[1]);
    const auto a = answer_similarity(t, d.feature(q[0]), d.feature(q[1]), d.feature(q[2]),
                                     d.feature_count(), answers ? *answers : rng);
    if (!a) {
      ++s.skipped;
      continue;
    }
    s.idx.insert(s.idx.end(), {q[a->p1], q[a->p2], q[a->neg]});
    ++s.count;
  }
  return s;
}

namespace {
// `exclude`: unordered pairs (smaller row first) that are drawn again.
void append_pairs(const Dataset& d, int64_t n, const RewardSet& r, int row, const Teacher& t,
                  Rng& rng, Rng& answers, PreferenceSet& s,
                  const std::set<std::pair<int32_t, int32_t>>* exclude = nullptr) {
  int64_t done = 0, attempts = 0;
  while (done < n) {
    check_attempts(++attempts, n, "preference queries");
    const int32_t a = int32_t(rng.uniform_int(d.count));
    int32_t b;
    do b = int32_t(rng.uniform_int(d.count));
    while (b == a);
    if (exclude && exclude->count({std::min(a, b), std::max(a, b)})) continue;
    const auto l = answer_preference(t, r.weights.data() + size_t(row) * r.dim, d.feature(a),
                                     d.feature(b), d.feature_count(), answers);
    if (!l) {
      ++s.skipped;
      continue;
    }
    s.pairs.insert(s.pairs.end(), {a, b});
    s.label.push_back(*l);
    s.human.push_back(row);
    ++s.count;
    ++done;
  }
}
}  // namespace

PreferenceSet sample_preference_queries(const Dataset& d, int64_t N, const RewardSet& r,
                                        const Teacher& t, Rng& rng, Rng* answers) {
  check_sample_size(d, N, 2, "preference queries");
  validate(t, d.feature_count());
  if (r.dim != d.feature_count())
    throw std::invalid_argument("reward set " + r.name + " has " + std::to_string(r.dim) +
                                " weights, the dataset " + std::to_string(d.feature_count()) +
                                " features");
  PreferenceSet s;
  const int K = r.count;
  for (int k = 0; k < K; ++k)
    append_pairs(d, N / K + (k < N % K ? 1 : 0), r, k, t, rng, answers ? *answers : rng, s);
  return s;
}

TripletSet first_triplets(const TripletSet& s, int64_t N) {
  if (N < 0 || N > s.count)
    throw std::invalid_argument("asked for " + std::to_string(N) +
                                " similarity queries, the set has " + std::to_string(s.count));
  TripletSet r;
  r.idx.assign(s.idx.begin(), s.idx.begin() + 3 * N);
  r.count = N;
  return r;
}

PreferenceSet take_per_human(const PreferenceSet& s, int64_t N, int K) {
  if (K < 1) throw std::invalid_argument("take_per_human: K must be >= 1");
  if (N < 0) throw std::invalid_argument("take_per_human: negative query count");
  std::vector<int64_t> have(K, 0);
  for (int64_t i = 0; i < s.count; ++i) {
    const int h = s.human[i];
    if (h < 0 || h >= K)
      throw std::invalid_argument("take_per_human: human " + std::to_string(h) + " outside [0, " +
                                  std::to_string(K) + ")");
    ++have[h];
  }
  PreferenceSet r;
  std::vector<int64_t> taken(K, 0);
  for (int64_t i = 0; i < s.count; ++i) {
    const int h = s.human[i];
    if (taken[h] >= N / K + (h < N % K ? 1 : 0)) continue;
    ++taken[h];
    r.pairs.push_back(s.pairs[2 * i]);
    r.pairs.push_back(s.pairs[2 * i + 1]);
    r.label.push_back(s.label[i]);
    r.human.push_back(h);
  }
  for (int k = 0; k < K; ++k)
    if (taken[k] != N / K + (k < N % K ? 1 : 0))
      throw std::invalid_argument("asked for " + std::to_string(N) + " preference queries over " +
                                  std::to_string(K) + " humans, human " + std::to_string(k) +
                                  " has only " + std::to_string(have[k]));
  r.count = int64_t(r.label.size());
  return r;
}

TpaSet sample_tpa_set(const Dataset& d, int64_t total, const RewardSet& r, int row,
                      const Teacher& t, Rng& rng, double train_fraction, Rng* answers) {
  check_sample_size(d, total, 2, "TPA pairs");
  validate(t, d.feature_count());
  if (row < 0 || row >= r.count) throw std::invalid_argument("TPA reward row out of range");
  TpaSet s;
  s.train = std::min<int64_t>(total, std::llround(train_fraction * double(total)));
  append_pairs(d, s.train, r, row, t, rng, answers ? *answers : rng, s.pairs);
  std::set<std::pair<int32_t, int32_t>> seen;
  for (int64_t i = 0; i < s.pairs.count; ++i) {
    const int32_t a = s.pairs.pairs[size_t(2 * i)], b = s.pairs.pairs[size_t(2 * i + 1)];
    seen.insert({std::min(a, b), std::max(a, b)});
  }
  const Teacher truth;  // the held-out pairs: the true reward's labels (draws nothing)
  append_pairs(d, total - s.train, r, row, truth, rng, rng, s.pairs, &seen);
  return s;
}

int64_t tpa_train_count(int64_t total) {
  return int64_t(std::llround(kTrainFraction * double(total)));
}

FpeSplit sample_fpe_split(const Dataset& d, int64_t total, Rng& rng, double train_fraction) {
  if (total < 2 || total > d.count)
    throw std::invalid_argument("FPE set size must be in [2, " + std::to_string(d.count) +
                                "], got " + std::to_string(total));
  std::vector<int32_t> all(d.count);
  std::iota(all.begin(), all.end(), 0);
  // Partial Fisher–Yates: the first `total` entries become a uniform random subset, shuffled.
  for (int64_t i = 0; i < total; ++i)
    std::swap(all[i], all[i + int64_t(rng.uniform_int(d.count - i))]);
  const int64_t ntr =
      std::clamp<int64_t>(std::llround(train_fraction * double(total)), 1, total - 1);
  return FpeSplit{std::vector<int32_t>(all.begin(), all.begin() + ntr),
                  std::vector<int32_t>(all.begin() + ntr, all.begin() + total)};
}

}  // namespace sirl
