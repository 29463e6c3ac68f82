// The preference baselines (paper §4.3: MultiPref-K, SinglePref): a shared φ and one linear
// reward head per human, trained on N preference pairs of the method's own set (N/K per human).
#include <algorithm>
#include <cmath>
#include <vector>

#include "datasets/query_bundle.h"
#include "engine/epochs.h"
#include "engine/method_trainers.h"
#include "engine/methods.h"
#include "engine/train_step.h"
#include "kernels/rng.h"

namespace sirl {

void train_preferences(const Dataset& d, const QueryBundle& bundle, const MethodConfig& cfg,
                       uint64_t seed, const Execution& ex, Representation& rep) {
  // The answers and the number of humans K (one reward head each) of the method's own set.
  const MethodTraining& how = method_spec(cfg.method).training;
  const PreferenceSet* full = &(bundle.*how.preferences);
  const int K = (bundle.rewards.*how.humans).count;
  const PreferenceSet q = take_per_human(*full, cfg.queries, K);
  const TrainSchedule& s = cfg.hyper.pref;
  const int dim = rep.dim();
  // Heads: K × (w [d], c), PyTorch nn.Linear(d, 1) initialisation.
  std::vector<float> params = rep.params;
  const size_t P = params.size();
  params.resize(P + size_t(K) * (dim + 1));
  Rng head_rng(seed_from_key("pref_heads", seed));
  const MlpShape head{{dim, 1}};
  for (int k = 0; k < K; ++k) mlp_init(head, params.data() + P + size_t(k) * (dim + 1), head_rng);
  Trainer t(rep.shape, s.adam, std::move(params));
  Rng order_rng(seed_from_key("pref_order", seed));
  std::vector<int32_t> pairs, human;
  std::vector<float> label;
  const ResumableState resume =
      adam_resumable(ex.checkpointer, "pref", t.params, t.adam, rep.train_flops);
  rep.loss_curve = run_epochs(
      q.count, s.epochs, s.batch, order_rng,
      [&](const int32_t* rows, int b) {
        pairs.resize(size_t(2) * b);
        label.resize(b);
        human.resize(b);
        for (int i = 0; i < b; ++i) {
          const int64_t j = rows[i];
          pairs[2 * i] = q.pairs[2 * j];
          pairs[2 * i + 1] = q.pairs[2 * j + 1];
          label[i] = q.label[j];
          human[i] = q.human[j];
        }
        rep.train_flops += t.shape.train_flops(2 * b);
        return multihead_preference_train_step(
            t, 0, adam_begin_step(s.adam, t.adam), K, d.inputs.data(), pairs.data(), label.data(),
            human.data(), b, float(cfg.hyper.pref_l2), ex.threads);
      },
      &resume, {},
      StopRule{cfg.hyper.pref_stop == "converged", cfg.hyper.pref_stop_min_epochs,
               cfg.hyper.pref_stop_rel_tol});
  // A training that stopped by pref.stop after k epochs is the fixed run of k epochs: its curve
  // holds the k epochs it ran, and the protocol's count adds the epochs it did not (every epoch
  // has the same batches, so the same FLOPs).
  const auto ran = std::find_if(rep.loss_curve.begin(), rep.loss_curve.end(),
                                [](float x) { return std::isnan(x); });
  if (ran != rep.loss_curve.end()) {
    const double k = double(ran - rep.loss_curve.begin());
    rep.skipped_flops = rep.train_flops / k * (double(s.epochs) - k);
    rep.loss_curve.erase(ran, rep.loss_curve.end());
  }
  rep.params.assign(t.params.begin(), t.params.begin() + P);  // φ; the heads on the side
  rep.heads.assign(t.params.begin() + P, t.params.end());
}

}  // namespace sirl
