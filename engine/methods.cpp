#include "engine/methods.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "engine/method_catalog.h"
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
  // external, truth, raw: φ(Ξ) is given (table_representation, reference_representation), never
  // trained; an untrained network under their name would be a silent wrong result.
  if (cfg.method == Method::external || is_reference(cfg.method))
    throw std::invalid_argument(std::string(method_name(cfg.method)) +
                                " is not trained: its embedding of Ξ is given");
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
  // Random's φ is its initialisation; every other method here trains it its own way.
  if (const auto train = method_spec(cfg.method).training.train)
    train(d, bundle, cfg, seed, ex, rep);
  require_finite(rep.loss_curve, what + " loss");
  require_finite(rep.params, what + " weights");
  return rep;
}

}  // namespace sirl
