#include "engine/tpa.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "engine/convergence.h"
#include "engine/epochs.h"
#include "engine/train_step.h"
#include "kernels/bradley_terry_loss.h"
#include "kernels/rng.h"

namespace sirl {

MlpShape tpa_network(const MlpShape& phi, const Hyper& h, bool frozen) {
  MlpShape s;
  if (frozen) {
    s.widths = {phi.out()};
  } else {
    s.widths = phi.widths;
    if (!phi.relu_on_output) s.linear_layers = {phi.layers() - 1};
    s.linear_layers.insert(s.linear_layers.end(), phi.linear_layers.begin(),
                           phi.linear_layers.end());
  }
  for (int w : h.tpa_hidden) s.widths.push_back(w);
  s.widths.push_back(1);
  s.bf16_products = bf16_products(h);
  validate(s);
  return s;
}

namespace {

void check_sets(const std::vector<TpaSet>& sets, int64_t M) {
  if (sets.empty()) throw std::invalid_argument("TPA needs at least one test reward");
  for (size_t r = 0; r < sets.size(); ++r) {
    const TpaSet& s = sets[r];
    if (M < 1 || M > s.train)
      throw std::invalid_argument("TPA M=" + std::to_string(M) + " outside [1, " +
                                  std::to_string(s.train) + "] for test reward " +
                                  std::to_string(r));
    if (s.pairs.count <= s.train)
      throw std::invalid_argument("TPA test reward " + std::to_string(r) +
                                  " has no held-out pairs");
  }
}

// The rows of Ξ a cell touches, compacted: X [U, w] holds raw inputs (unfrozen) or φ(ξ) (frozen),
// and every reward's training pairs (its first M) and held-out pairs are remapped into it.
struct CellRows {
  std::vector<float> X;
  std::vector<std::vector<int32_t>> train, test;  // [R][2·pairs] rows of X
};

CellRows compact_rows(const Representation& rep, const Dataset& d, const std::vector<TpaSet>& sets,
                      const TpaConfig& cfg, int threads) {
  const size_t R = sets.size();
  std::vector<int32_t> compact(d.count, -1), used;
  auto remap = [&](int32_t row) {
    if (compact[row] < 0) {
      compact[row] = int32_t(used.size());
      used.push_back(row);
    }
    return compact[row];
  };
  CellRows c;
  c.train.resize(R);
  c.test.resize(R);
  for (size_t r = 0; r < R; ++r) {
    const auto& p = sets[r].pairs.pairs;
    for (int64_t i = 0; i < 2 * cfg.M; ++i) c.train[r].push_back(remap(p[i]));
    for (int64_t i = 2 * sets[r].train; i < 2 * sets[r].pairs.count; ++i)
      c.test[r].push_back(remap(p[i]));
  }
  if (cfg.frozen) {
    c.X = embed_rows(rep, d, used, threads);
    require_finite(c.X, "TPA: φ(ξ)");
  } else {
    const int64_t U = int64_t(used.size());
    c.X.resize(size_t(U) * d.input_dim);
    for (int64_t u = 0; u < U; ++u)
      std::copy(d.input(used[u]), d.input(used[u]) + d.input_dim, c.X.begin() + u * d.input_dim);
  }
  return c;
}

// Every head's initial weights [R, P]: φ's (unfrozen) followed by a fresh head from the stream
// "tpa_head/<r>" of `seed`.
std::vector<float> initial_heads(const Representation& rep, const TpaConfig& cfg, size_t R,
                                 const MlpShape& net, uint64_t seed) {
  const size_t P = net.param_count(), P_phi = cfg.frozen ? 0 : rep.params.size();
  const MlpShape head_only = tpa_network(rep.shape, cfg.hyper, true);
  std::vector<float> init(R * P);
  for (size_t r = 0; r < R; ++r) {
    float* p = init.data() + r * P;
    if (!cfg.frozen) std::copy(rep.params.begin(), rep.params.end(), p);
    Rng rng(seed_from_key("tpa_head/" + std::to_string(r), seed));
    mlp_init(head_only, p + P_phi, rng);  // the head's layers follow φ's in the flat layout
  }
  return init;
}

// A head's accuracy (params p [P]) on `pairs` [2n] of rows.X with their labels [n]; tape and xb
// are the caller's scratch.
double head_accuracy(const MlpShape& net, const float* p, const CellRows& rows,
                     const std::vector<int32_t>& pairs, const float* labels, MlpTape<float>& tape,
                     std::vector<float>& xb, int threads) {
  const int n = int(pairs.size() / 2), w = net.in();
  xb.resize(size_t(2) * n * w);
  gather_by_role(rows.X.data(), w, pairs.data(), n, 2, xb.data());
  mlp_forward(net, p, xb.data(), 2 * n, tape, threads);
  return preference_accuracy(tape.output(), labels, n);
}

// Each head's held-out and training accuracy, how far its copy of φ moved (unfrozen), and the
// cell's mean and standard deviation over heads. params: [R, P] (φ's weights first, unfrozen).
void score_heads(const MlpShape& net, const std::vector<float>& params, const Representation& rep,
                 const CellRows& rows, const std::vector<TpaSet>& sets, const TpaConfig& cfg,
                 int threads, TpaResult& res) {
  const int R = int(sets.size());
  const size_t P = net.param_count(), P_phi = cfg.frozen ? 0 : rep.params.size();
  MlpTape<float> tape;
  std::vector<float> xb;
  res.accuracy.resize(R);
  res.train_accuracy.resize(R);
  res.phi_drift.assign(R, 0.f);
  auto accuracy_on = [&](const float* p, const std::vector<int32_t>& pairs, const float* labels) {
    return head_accuracy(net, p, rows, pairs, labels, tape, xb, threads);
  };
  for (int r = 0; r < R; ++r) {
    const float* p = params.data() + size_t(r) * P;
    res.accuracy[r] = accuracy_on(p, rows.test[r], sets[r].pairs.label.data() + sets[r].train);
    res.train_accuracy[r] = accuracy_on(p, rows.train[r], sets[r].pairs.label.data());
    for (size_t i = 0; i < P_phi; ++i)
      res.phi_drift[r] = std::max(res.phi_drift[r], std::abs(p[i] - rep.params[i]));
  }
  double sum = 0;
  for (double a : res.accuracy) sum += a;
  res.mean = sum / R;
  double ss = 0;
  for (double a : res.accuracy) ss += (a - res.mean) * (a - res.mean);
  res.stddev = R > 1 ? std::sqrt(ss / (R - 1)) : 0.0;
}

}  // namespace

TpaResult evaluate_tpa(const Representation& rep, const Dataset& d, const std::vector<TpaSet>& sets,
                       const TpaConfig& cfg, uint64_t seed, const Execution& ex) {
  validate(cfg.hyper);
  check_sets(sets, cfg.M);
  if (rep.is_table() && !cfg.frozen)
    throw std::invalid_argument(
        "TPA: an external representation has no weights to fine-tune (frozen cells only)");
  const int R = int(sets.size());
  const int64_t M = cfg.M;
  const CellRows rows = compact_rows(rep, d, sets, cfg, ex.threads);
  const Hyper& h = cfg.hyper;
  const MlpShape net = tpa_network(rep.shape, h, cfg.frozen);
  Trainer t(net, h.tpa.adam, initial_heads(rep, cfg, size_t(R), net, seed), R);

  std::vector<Rng> order_rng;
  for (int r = 0; r < R; ++r)
    order_rng.emplace_back(seed_from_key("tpa_order/" + std::to_string(r), seed));
  TpaResult res;
  res.epochs = h.tpa.epochs;
  // Each head's pairs and labels of its current batch, [R][2b] and [R][b].
  std::vector<std::vector<int32_t>> pairs(R);
  std::vector<std::vector<float>> label(R);
  // Every epoch has the same batches: 3 passes of each batch's 2b rows through R networks (a
  // head's share: epoch_flops / R).
  const double epoch_flops = epoch_train_flops(net, M, h.tpa.batch, 2, R);
  const int64_t batches = (M + h.tpa.batch - 1) / h.tpa.batch;
  const ResumableState resume =
      adam_resumable(ex.checkpointer, "tpa", t.params, t.adam, res.train_flops);
  // Head by head: each head's steps in a row, so more of its weights and moments stay in cache
  // (the same bits as stepping all heads at once). Under tpa.stop = "converged" a head whose loss
  // has converged takes no further step.
  EpochLoopOptions loop;
  loop.resume = &resume;
  loop.threads = ex.threads;
  loop.stretch_steps = ex.stretch_steps;
  loop.stop = tpa_stop_rule(h, cfg.frozen);
  // The shadow rule: each head scored where that rule would have stopped it, kept in checkpoints
  // (numbers "tpa/shadow/<r>/epochs" and ".../accuracy") since the weights then are gone.
  ResumableState shadow_resume = resume;
  if (const StopRule shadow = tpa_shadow_rule(h, cfg.frozen); shadow.converged) {
    res.shadow_epochs.assign(size_t(R), 0);
    res.shadow_accuracy.assign(size_t(R), 0.0);
    const size_t P = net.param_count();
    loop.shadow = shadow;
    loop.at_shadow_stop = [&, P](int r, int done) {
      MlpTape<float> tape;  // the heads train on several threads: scratch of its own
      std::vector<float> xb;
      res.shadow_epochs[r] = done;
      res.shadow_accuracy[r] =
          head_accuracy(net, t.params.data() + size_t(r) * P, rows, rows.test[r],
                        sets[r].pairs.label.data() + sets[r].train, tape, xb, 1);
    };
    const auto name = [](int r, const char* what) {
      return "tpa/shadow/" + std::to_string(r) + "/" + what;
    };
    shadow_resume.save = [&, name, base = resume.save](TrainingSnapshot& s) {
      if (base) base(s);
      for (int r = 0; r < R; ++r) {
        s.numbers[name(r, "epochs")] = res.shadow_epochs[r];
        s.numbers[name(r, "accuracy")] = res.shadow_accuracy[r];
      }
    };
    shadow_resume.restore = [&, name, base = resume.restore](const TrainingSnapshot& s) {
      if (base) base(s);
      for (int r = 0; r < R; ++r) {
        res.shadow_epochs[r] = int(s.number(name(r, "epochs")));
        res.shadow_accuracy[r] = s.number(name(r, "accuracy"));
      }
    };
    loop.resume = &shadow_resume;
  }
  ModelCurves run = run_model_epochs(
      M, res.epochs, h.tpa.batch, order_rng,
      [&](int r, const int32_t* order, int b, int64_t step) {
        pairs[r].resize(size_t(b) * 2);
        label[r].resize(size_t(b));
        for (int i = 0; i < b; ++i) {
          const int64_t j = order[i];
          pairs[r][size_t(i) * 2] = rows.train[r][2 * j];
          pairs[r][size_t(i) * 2 + 1] = rows.train[r][2 * j + 1];
          label[r][i] = sets[r].pairs.label[j];
        }
        return preference_train_step(t, r, adam_step_scalars(h.tpa.adam, step), rows.X.data(),
                                     pairs[r].data(), label[r].data(), b, float(h.tpa_l2));
      },
      // Adam's step count is each head's own (the step function is handed it); the shared
      // counter is kept at the epoch every running head stands at, for checkpoints.
      [&](int e) { t.adam.step = e * batches; }, loop);
  res.loss_curves = std::move(run.curves);
  res.head_epochs = std::move(run.epochs_run);
  res.protocol_flops = double(res.epochs) * epoch_flops;
  res.train_flops = 0;
  for (int r = 0; r < R; ++r) {
    res.train_flops += double(res.head_epochs[r]) * epoch_flops / R;
    const float* c = res.loss_curves.data() + size_t(r) * res.epochs;
    require_finite(std::vector<float>(c, c + res.head_epochs[r]),
                   "TPA loss (frozen=" + std::to_string(cfg.frozen) + ")");
  }
  require_finite(t.params, "TPA head weights");

  score_heads(net, t.params, rep, rows, sets, cfg, ex.threads, res);
  if (!res.shadow_epochs.empty()) {
    double sum = 0;  // summed as score_heads sums a cell's accuracies
    for (int r = 0; r < R; ++r) {
      if (res.shadow_epochs[r] == 0) {  // never met the rule: the run to the cap is its run
        res.shadow_epochs[r] = res.epochs;
        res.shadow_accuracy[r] = res.accuracy[r];
      }
      sum += res.shadow_accuracy[r];
    }
    res.shadow_mean = sum / R;
  }
  return res;
}

}  // namespace sirl
