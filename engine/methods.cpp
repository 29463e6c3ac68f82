#include "engine/methods.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "engine/epochs.h"
#include "engine/train_step.h"
#include "kernels/rng.h"

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

void train_sirl(const Dataset& d, const QueryBundle& bundle, const MethodConfig& cfg, uint64_t seed,
                Representation& rep) {
  const TripletSet q = first_triplets(bundle.similarity, cfg.queries);
  const TrainSchedule& s = cfg.hyper.sirl;
  Trainer t(rep.shape, s.adam, rep.params);
  Rng order_rng(seed_from_key("sirl_order", seed));
  std::vector<int32_t> batch;
  const ResumableState resume =
      adam_resumable(cfg.checkpointer, "sirl", t.params, t.adam, rep.train_flops);
  rep.loss_curve = run_epochs(
      q.count, s.epochs, s.batch, order_rng,
      [&](const int32_t* rows, int b) {
        batch.resize(size_t(3) * b);
        for (int i = 0; i < b; ++i)
          std::copy_n(q.idx.begin() + 3 * rows[i], 3, batch.begin() + 3 * i);
        rep.train_flops += 3 * t.shape.forward_flops(3 * b);
        return triplet_train_step(t, d.inputs.data(), batch.data(), b,
                                  float(cfg.hyper.triplet_margin), cfg.threads);
      },
      &resume);
  rep.params = std::move(t.params);
}

void train_preference(const Dataset& d, const QueryBundle& bundle, const MethodConfig& cfg,
                      uint64_t seed, Representation& rep) {
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
      adam_resumable(cfg.checkpointer, "pref", t.params, t.adam, rep.train_flops);
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
        rep.train_flops += 3 * t.shape.forward_flops(2 * b);
        return multihead_preference_train_step(t, K, d.inputs.data(), pairs.data(), label.data(),
                                               human.data(), b, float(cfg.hyper.pref_l2),
                                               cfg.threads);
      },
      &resume);
  rep.params.assign(t.params.begin(), t.params.begin() + P);  // φ; the heads on the side
  rep.heads.assign(t.params.begin() + P, t.params.end());
}

}  // namespace

Representation train_representation(const Dataset& d, const QueryBundle& bundle,
                                    const MethodConfig& cfg, uint64_t seed, const VaeModel* vae) {
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
    train_sirl(d, bundle, cfg, seed, rep);
  else if (cfg.method != Method::random)
    train_preference(d, bundle, cfg, seed, rep);
  require_finite(rep.loss_curve, what + " loss");
  require_finite(rep.params, what + " weights");
  return rep;
}

}  // namespace sirl
