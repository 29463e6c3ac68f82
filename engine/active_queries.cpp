#include "engine/active_queries.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>
#include <stdexcept>

#include "engine/epochs.h"
#include "engine/representation.h"
#include "engine/train_step.h"
#include "kernels/mlp.h"
#include "kernels/rng.h"

namespace sirl {

double vote_entropy(const int* votes, int K) {
  std::array<int, 3> n{};
  for (int k = 0; k < K; ++k) ++n[size_t(votes[k])];
  double h = 0;
  for (int c : n)
    if (c > 0) h -= double(c) / K * std::log(double(c) / K);
  return h;
}

namespace {
double entropy3(const double* p) {
  double h = 0;
  for (int j = 0; j < 3; ++j)
    if (p[j] > 0) h -= p[j] * std::log(p[j]);
  return h;
}
}  // namespace

double mutual_information(const double* probs, int K) {
  std::array<double, 3> mean{};
  double mean_h = 0;
  for (int k = 0; k < K; ++k) {
    for (int j = 0; j < 3; ++j) mean[size_t(j)] += probs[3 * k + j] / K;
    mean_h += entropy3(probs + 3 * k) / K;
  }
  return std::max(0.0, entropy3(mean.data()) - mean_h);
}

std::array<double, 3> crowd_kernel_probs(const std::array<double, 3>& d, double mu) {
  std::array<double, 3> p;
  double z = 0;
  for (int j = 0; j < 3; ++j) z += p[size_t(j)] = 1.0 / (mu + d[size_t(j)]);
  for (double& v : p) v /= z;
  return p;
}

namespace {

using Triple = std::array<int32_t, 3>;

Triple sorted(const int32_t* t) {
  Triple s{t[0], t[1], t[2]};
  std::sort(s.begin(), s.end());
  return s;
}

// A uniform triplet of distinct rows that is not in `seen` (nor `also`).
Triple draw_new(const Dataset& d, Rng& rng, const std::set<Triple>& seen,
                const std::set<Triple>& also) {
  for (int attempt = 0; attempt < 100000; ++attempt) {
    Triple q;
    q[0] = int32_t(rng.uniform_int(d.count));
    do q[1] = int32_t(rng.uniform_int(d.count));
    while (q[1] == q[0]);
    do q[2] = int32_t(rng.uniform_int(d.count));
    while (q[2] == q[0] || q[2] == q[1]);
    const Triple s = sorted(q.data());
    if (!seen.count(s) && !also.count(s)) return q;
  }
  throw std::runtime_error("active selection: Ξ has no triplet left that was not asked");
}

struct Ensemble {
  Trainer trainer;
  std::vector<Rng> order;
};

Ensemble make_ensemble(const MlpShape& shape, const ActiveConfig& cfg, uint64_t seed) {
  const size_t P = shape.param_count();
  std::vector<float> init(P * size_t(cfg.members));
  std::vector<Rng> order;
  for (int k = 0; k < cfg.members; ++k) {
    Rng rng(seed_from_key("active/member/" + std::to_string(k), seed));
    mlp_init(shape, init.data() + size_t(k) * P, rng);
    order.emplace_back(seed_from_key("active/order/" + std::to_string(k), seed));
  }
  return {Trainer(shape, cfg.hyper.sirl.adam, std::move(init), cfg.members), std::move(order)};
}

// Scores [pool] of the candidate triplets under the members' embeddings.
std::vector<double> score_pool(const Dataset& d, const std::vector<Triple>& pool, Trainer& ens,
                               const ActiveConfig& cfg, int threads, double& flops) {
  const MlpShape& shape = ens.shape;
  const int K = ens.models, dim = shape.out(), in = shape.in();
  // The distinct rows of the pool, embedded once per member.
  std::vector<int32_t> rows;
  for (const Triple& t : pool) rows.insert(rows.end(), t.begin(), t.end());
  std::sort(rows.begin(), rows.end());
  rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
  std::vector<float> X(rows.size() * size_t(in)), emb(size_t(K) * rows.size() * dim);
  for (size_t i = 0; i < rows.size(); ++i) std::copy_n(d.input(rows[i]), in, X.begin() + i * in);
  const size_t P = shape.param_count();
  for (int k = 0; k < K; ++k) {
    Representation rep;
    rep.shape = shape;
    rep.params.assign(ens.params.begin() + k * P, ens.params.begin() + (k + 1) * P);
    embed(rep, X.data(), int64_t(rows.size()), emb.data() + size_t(k) * rows.size() * dim, threads);
    flops += shape.forward_flops(int(rows.size()));
  }
  auto at = [&](int k, int32_t row) {
    const size_t i = size_t(std::lower_bound(rows.begin(), rows.end(), row) - rows.begin());
    return emb.data() + (size_t(k) * rows.size() + i) * dim;
  };
  auto dist = [&](const float* a, const float* b) {
    double s = 0;
    for (int j = 0; j < dim; ++j) s += double(a[j] - b[j]) * (a[j] - b[j]);
    return s;
  };
  // Each member's distances [pool, 3] and its median pair distance (μ's unit).
  std::vector<double> dd(size_t(K) * pool.size() * 3), median(static_cast<size_t>(K), 0.0);
  for (int k = 0; k < K; ++k) {
    for (size_t q = 0; q < pool.size(); ++q) {
      const float *a = at(k, pool[q][0]), *b = at(k, pool[q][1]), *c = at(k, pool[q][2]);
      double* o = dd.data() + (size_t(k) * pool.size() + q) * 3;
      o[0] = dist(a, b), o[1] = dist(a, c), o[2] = dist(b, c);
    }
    std::vector<double> all(dd.begin() + size_t(k) * pool.size() * 3,
                            dd.begin() + size_t(k + 1) * pool.size() * 3);
    std::nth_element(all.begin(), all.begin() + all.size() / 2, all.end());
    median[size_t(k)] = std::max(all[all.size() / 2], 1e-12);
  }
  std::vector<double> score(pool.size());
  std::vector<int> votes(static_cast<size_t>(K), 0);
  std::vector<double> probs(static_cast<size_t>(K) * 3, 0.0);
  for (size_t q = 0; q < pool.size(); ++q) {
    for (int k = 0; k < K; ++k) {
      const double* o = dd.data() + (size_t(k) * pool.size() + q) * 3;
      votes[size_t(k)] = int(std::min_element(o, o + 3) - o);
      const auto p = crowd_kernel_probs({o[0], o[1], o[2]}, cfg.mu * median[size_t(k)]);
      std::copy(p.begin(), p.end(), probs.begin() + 3 * k);
    }
    score[q] = cfg.rule == Selection::vote       ? vote_entropy(votes.data(), K)
               : cfg.rule == Selection::infogain ? mutual_information(probs.data(), K)
                                                 : 0.0;
  }
  return score;
}

void check_config(const Dataset& d, const ActiveConfig& c) {
  if (c.members < 2) throw std::invalid_argument("active selection needs at least 2 members");
  if (c.batch < 1 || c.pool < c.batch)
    throw std::invalid_argument("active selection: batch must be ≥ 1 and pool ≥ batch");
  if (c.round_epochs < 1) throw std::invalid_argument("active selection: round_epochs must be ≥ 1");
  if (!(c.mu > 0)) throw std::invalid_argument("active selection: mu must be > 0");
  const double triples = double(d.count) * (d.count - 1) * (d.count - 2) / 6;
  if (c.budget < 1 || double(c.budget + c.pool) > triples / 2)
    throw std::invalid_argument("active selection: a budget of " + std::to_string(c.budget) +
                                " triplets (plus a pool of " + std::to_string(c.pool) +
                                ") is too many for a Ξ of " + std::to_string(d.count));
}

// One selection's state: the ensemble, the two random streams, the queries answered and every
// triple ever asked. run() is the paper's loop of rounds; a checkpoint saves and restores all of
// it between rounds.
class ActiveSelection {
 public:
  ActiveSelection(const Dataset& d, const Teacher& teacher, const ActiveConfig& cfg, uint64_t seed,
                  const Execution& ex)
      : d_(d),
        teacher_(teacher),
        cfg_(cfg),
        ex_(ex),
        shape_(phi_shape(d.input_dim, cfg.hyper)),
        ens_(make_ensemble(shape_, cfg, seed)),
        pool_rng_(seed_from_key("active/pool", seed)),
        answer_rng_(seed_from_key("active/answers", seed)) {}

  ActiveQueries run() {
    // A rerun continues from the last round saved.
    if (TrainingSnapshot s; ex_.checkpointer && ex_.checkpointer->load(s)) restore(s);
    while (out_.queries.count < cfg_.budget) {
      const int64_t before = out_.queries.count;
      const int64_t want = std::min(cfg_.batch, cfg_.budget - out_.queries.count);
      const std::vector<Triple> pool = draw_pool(out_.rounds == 0 ? want : cfg_.pool);
      if (out_.rounds == 0) {  // nothing learned yet: a uniform first batch
        for (const Triple& q : pool) ask(q);
        check_answered(before);
        out_.batch_score.push_back(0.f);
        out_.pool_score.push_back(0.f);
      } else {
        // Train the members on everything answered so far, then score the pool.
        train_members();
        const std::vector<double> score =
            score_pool(d_, pool, ens_.trainer, cfg_, ex_.threads, out_.train_flops);
        const double picked = ask_best(pool, score, want);
        double pool_mean = 0;
        for (double v : score) pool_mean += v / double(score.size());
        check_answered(before);
        out_.batch_score.push_back(float(picked));
        out_.pool_score.push_back(float(pool_mean));
      }
      ++out_.rounds;
      if (ex_.checkpointer && out_.queries.count < cfg_.budget && ex_.checkpointer->due()) save();
    }
    return out_;
  }

 private:
  // Asks the teacher; false: it skipped the query (which stays asked).
  bool ask(const Triple& q) {
    asked_.insert(sorted(q.data()));
    const auto a = answer_similarity(teacher_, d_.feature(q[0]), d_.feature(q[1]), d_.feature(q[2]),
                                     d_.feature_count(), answer_rng_);
    if (!a) {
      ++out_.queries.skipped;
      return false;
    }
    out_.queries.idx.insert(out_.queries.idx.end(),
                            {q[size_t(a->p1)], q[size_t(a->p2)], q[size_t(a->neg)]});
    ++out_.queries.count;
    return true;
  }

  // A teacher who withholds every answer of a round would make the loop spin forever.
  void check_answered(int64_t before) const {
    if (out_.queries.count == before)
      throw std::runtime_error("active selection: the teacher skipped every query of round " +
                               std::to_string(out_.rounds) + "; lower its skip threshold");
  }

  // `size` triples never asked, none twice.
  std::vector<Triple> draw_pool(int64_t size) {
    std::vector<Triple> pool;
    std::set<Triple> in_pool;
    for (int64_t i = 0; i < size; ++i) {
      pool.push_back(draw_new(d_, pool_rng_, asked_, in_pool));
      in_pool.insert(sorted(pool.back().data()));
    }
    return pool;
  }

  // One round's epochs of every member on the n queries answered so far, member by member (each
  // its own order stream; Adam's step count goes on from the rounds before).
  void train_members() {
    const int64_t n = out_.queries.count;
    const int B = cfg_.hyper.sirl.batch;
    const float margin = float(cfg_.hyper.triplet_margin);
    Trainer& ens = ens_.trainer;
    const int64_t step0 = ens.adam.step, batches = (n + B - 1) / B;
    member_batch_.resize(size_t(cfg_.members));
    EpochLoopOptions loop;
    loop.threads = ex_.threads;
    loop.stretch_steps = ex_.stretch_steps;
    run_model_epochs(
        n, cfg_.round_epochs, B, ens_.order,
        [&](int k, const int32_t* order, int b, int64_t step) {
          std::vector<int32_t>& batch = member_batch_[size_t(k)];
          batch.resize(size_t(b) * 3);
          for (int i = 0; i < b; ++i)
            std::copy_n(out_.queries.idx.begin() + 3 * order[i], 3, batch.begin() + size_t(i) * 3);
          return triplet_train_step(ens, k, adam_step_scalars(ens.adam_cfg, step0 + step),
                                    d_.inputs.data(), batch.data(), b, margin);
        },
        [&](int e) { ens.adam.step = step0 + e * batches; }, loop);
    for (int e = 0; e < cfg_.round_epochs; ++e)  // the round's FLOPs
      out_.train_flops = epoch_train_flops(shape_, n, B, 3, cfg_.members, out_.train_flops);
    for (float v : ens_.trainer.params)
      if (!std::isfinite(v))
        throw std::runtime_error("active selection: an ensemble member diverged");
  }

  // Asks up to `want` of the pool, best score first, no trajectory twice in one batch while the
  // pool allows it. Returns the mean score of the answered ones (0 if none).
  double ask_best(const std::vector<Triple>& pool, const std::vector<double>& score, int64_t want) {
    std::vector<size_t> rank(pool.size());
    std::iota(rank.begin(), rank.end(), 0);
    std::stable_sort(rank.begin(), rank.end(),
                     [&](size_t a, size_t b) { return score[a] > score[b]; });
    std::set<int32_t> used;
    std::vector<bool> taken(pool.size(), false);
    double picked = 0;
    int64_t got = 0;
    for (int pass = 0; pass < 2 && got < want; ++pass)
      for (size_t r : rank) {
        if (got >= want) break;
        if (taken[r]) continue;
        const Triple& q = pool[r];
        if (pass == 0 && (used.count(q[0]) || used.count(q[1]) || used.count(q[2]))) continue;
        taken[r] = true;
        used.insert(q.begin(), q.end());
        if (ask(q)) {
          ++got;
          picked += score[r];
        }
      }
    return got ? picked / double(got) : 0.0;
  }

  void restore(const TrainingSnapshot& s) {
    out_.rounds = s.epoch;
    const auto& w = s.words.at("active/queries");
    out_.queries.idx.assign(w.begin(), w.end());
    out_.queries.count = int64_t(out_.queries.idx.size() / 3);
    out_.queries.skipped = int64_t(s.number("active/skipped"));
    const auto& aw = s.words.at("active/asked");
    for (size_t i = 0; i + 2 < aw.size(); i += 3)
      asked_.insert({int32_t(aw[i]), int32_t(aw[i + 1]), int32_t(aw[i + 2])});
    out_.batch_score = s.get("active/batch_score", size_t(out_.rounds));
    out_.pool_score = s.get("active/pool_score", size_t(out_.rounds));
    out_.train_flops = s.number("active/flops");
    get_adam(s, "active/members", ens_.trainer.params, ens_.trainer.adam);
    s.get_rng("active/pool_rng", pool_rng_);
    s.get_rng("active/answer_rng", answer_rng_);
    for (int k = 0; k < cfg_.members; ++k)
      s.get_rng("active/order/" + std::to_string(k), ens_.order[size_t(k)]);
  }

  void save() {
    TrainingSnapshot s;
    s.epoch = out_.rounds;
    s.words["active/queries"].assign(out_.queries.idx.begin(), out_.queries.idx.end());
    auto& aw = s.words["active/asked"];
    for (const Triple& t : asked_) aw.insert(aw.end(), t.begin(), t.end());
    s.numbers["active/skipped"] = double(out_.queries.skipped);
    s.numbers["active/flops"] = out_.train_flops;
    s.floats["active/batch_score"] = out_.batch_score;
    s.floats["active/pool_score"] = out_.pool_score;
    put_adam(s, "active/members", ens_.trainer.params, ens_.trainer.adam);
    s.put_rng("active/pool_rng", pool_rng_);
    s.put_rng("active/answer_rng", answer_rng_);
    for (int k = 0; k < cfg_.members; ++k)
      s.put_rng("active/order/" + std::to_string(k), ens_.order[size_t(k)]);
    ex_.checkpointer->save(s);
  }

  const Dataset& d_;
  const Teacher& teacher_;
  const ActiveConfig& cfg_;
  const Execution& ex_;
  const MlpShape shape_;
  Ensemble ens_;
  Rng pool_rng_, answer_rng_;
  ActiveQueries out_;
  std::set<Triple> asked_;
  std::vector<std::vector<int32_t>> member_batch_;  // [members][3b]: each member's batch
};

}  // namespace

ActiveQueries select_active_queries(const Dataset& d, const Teacher& teacher,
                                    const ActiveConfig& cfg, uint64_t seed, const Execution& ex) {
  check_config(d, cfg);
  validate(teacher, d.feature_count());
  return ActiveSelection(d, teacher, cfg, seed, ex).run();
}

}  // namespace sirl
