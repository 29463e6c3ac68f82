#include "engine/methods.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "engine/epochs.h"
#include "engine/train_step.h"
#include "kernels/rng.h"
#include "kernels/triplet_loss.h"

namespace sirl {

namespace {

std::vector<float> initial_phi(const Dataset& d, const MethodConfig& cfg, uint64_t seed,
                               const VaeModel* vae) {
  const MlpShape shape = phi_shape(d.input_dim, cfg.hyper);
  if (cfg.vae_pretrain) {
    Representation enc = vae_mean_encoder(*vae);
    if (enc.shape.widths != shape.widths)
      throw std::invalid_argument("the pre-trained VAE's encoder does not have φ's widths");
    return enc.params;
  }
  std::vector<float> p(shape.param_count());
  Rng rng(seed_from_key("phi_init", seed));
  mlp_init(shape, p.data(), rng);
  return p;
}

// Whether every value is exactly 0.
bool all_zero(const std::vector<float>& v) {
  return std::all_of(v.begin(), v.end(), [](float x) { return x == 0.f; });
}

// SIRL's triplet loss is a hinge: once every triplet is inside its margin, the loss and every
// gradient are exactly 0, Adam's first moments decay to exactly 0 (kernels/adam.h stores a moment
// below the smallest normal float as 0), and from then on every step leaves every weight bit
// unchanged. An epoch that starts with every first moment 0 and whose every triplet stays inside
// its margin by kFixedPointSlack·max(α, 1) therefore ends where it began, and so does every epoch
// after it: training skips to its end (run_epochs' at_fixed_point; the skipped epochs' loss is 0,
// as the full run's). The slack keeps the decision clear of rounding: a triplet's hinge is
// computed from its rows' embeddings, which another batch of the next epoch might round
// differently in the last bits.
constexpr float kFixedPointSlack = 1e-3f;

void train_sirl(const Dataset& d, const QueryBundle& bundle, const MethodConfig& cfg, uint64_t seed,
                const Execution& ex, Representation& rep) {
  const TripletSet q = first_triplets(bundle.similarity, cfg.queries);
  const TrainSchedule& s = cfg.hyper.sirl;
  Trainer t(rep.shape, s.adam, rep.params);
  Rng order_rng(seed_from_key("sirl_order", seed));
  std::vector<int32_t> batch;
  const ResumableState resume =
      adam_resumable(ex.checkpointer, "sirl", t.params, t.adam, rep.train_flops);
  const float margin = float(cfg.hyper.triplet_margin);
  const float inside = -kFixedPointSlack * std::max(margin, 1.f);
  // Per epoch: whether it started with every first moment 0, and whether every triplet so far
  // was inside its margin by the slack.
  bool epoch_start = true, moments_zero = false, idle = false;
  const double epoch_flops = epoch_train_flops(t.shape, q.count, s.batch, 3);  // every epoch's
  int skipped = 0;
  rep.loss_curve = run_epochs(
      q.count, s.epochs, s.batch, order_rng,
      [&](const int32_t* rows, int b) {
        if (epoch_start) {
          moments_zero = all_zero(t.adam.m);  // after a resume too: the restored moments
          idle = true;
          epoch_start = false;
        }
        batch.resize(size_t(3) * b);
        for (int i = 0; i < b; ++i)
          std::copy_n(q.idx.begin() + 3 * rows[i], 3, batch.begin() + 3 * i);
        rep.train_flops += t.shape.train_flops(3 * b);
        const float loss = triplet_train_step(t, 0, adam_begin_step(s.adam, t.adam),
                                              d.inputs.data(), batch.data(), b, margin, ex.threads);
        if (idle)
          idle = triplet_max_hinge(t.work[0].tape.output(), b, t.shape.out(), margin) <= inside;
        return loss;
      },
      &resume,
      [&](int done) {
        epoch_start = true;
        if (!(cfg.skip_fixed_point && moments_zero && idle)) return false;
        skipped = s.epochs - done;
        return true;
      });
  rep.skipped_flops = skipped * epoch_flops;
  rep.params = std::move(t.params);
}

void train_preference(const Dataset& d, const QueryBundle& bundle, const MethodConfig& cfg,
                      uint64_t seed, const Execution& ex, Representation& rep) {
  const PreferenceSet* full = nullptr;
  int K = 0;
  switch (cfg.method) {
    case Method::multipref10:
      full = &bundle.multipref10, K = bundle.rewards.multipref10.count;
      break;
    case Method::multipref50:
      full = &bundle.multipref50, K = bundle.rewards.multipref50.count;
      break;
    default:
      full = &bundle.singlepref, K = bundle.rewards.singlepref.count;
      break;
  }
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
      &resume);
  rep.params.assign(t.params.begin(), t.params.begin() + P);  // φ; the heads on the side
  rep.heads.assign(t.params.begin() + P, t.params.end());
}

}  // namespace

Representation train_representation(const Dataset& d, const QueryBundle& bundle,
                                    const MethodConfig& cfg, uint64_t seed, const VaeModel* vae,
                                    const Execution& ex) {
  validate(cfg.hyper);
  const bool needs_vae = cfg.method == Method::vae || cfg.vae_pretrain;
  if (needs_vae && !vae)
    throw std::invalid_argument(std::string(method_name(cfg.method)) +
                                (cfg.vae_pretrain ? " with VAE pre-training" : "") +
                                " needs a trained VAE");
  if (cfg.vae_pretrain && !accepts_vae_pretrain(cfg.method))
    throw std::invalid_argument(std::string("VAE pre-training is not a switch of ") +
                                method_name(cfg.method));
  if (uses_queries(cfg.method) && cfg.queries < 1)
    throw std::invalid_argument(std::string(method_name(cfg.method)) + " needs N >= 1 queries");
  if (cfg.method == Method::vae) {
    Representation r = vae_mean_encoder(*vae);
    r.shape.relu_on_output = false;
    return r;
  }
  Representation rep;
  rep.shape = phi_shape(d.input_dim, cfg.hyper);
  rep.params = initial_phi(d, cfg, seed, vae);
  rep.method = cfg.method;
  rep.vae_pretrain = cfg.vae_pretrain;
  rep.queries = uses_queries(cfg.method) ? cfg.queries : 0;
  const std::string what = std::string(method_name(cfg.method)) + (cfg.vae_pretrain ? "+vae" : "") +
                           " N=" + std::to_string(cfg.queries);
  if (cfg.method == Method::sirl)
    train_sirl(d, bundle, cfg, seed, ex, rep);
  else if (cfg.method != Method::random)
    train_preference(d, bundle, cfg, seed, ex, rep);
  require_finite(rep.loss_curve, what + " loss");
  require_finite(rep.params, what + " weights");
  return rep;
}

}  // namespace sirl
