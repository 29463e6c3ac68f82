#include "engine/train_vae.h"

#include <algorithm>

#include "engine/epochs.h"
#include "kernels/adam.h"
#include "kernels/rng.h"

namespace sirl {

VaeModel train_vae(const Dataset& d, const Hyper& h, uint64_t seed, int threads) {
  validate(h);
  VaeModel m;
  m.shape = make_vae_shape(d.input_dim, h.phi_hidden, h.embedding_dim);
  m.params.resize(m.shape.param_count());
  Rng init(seed_from_key("vae_init", seed)), noise(seed_from_key("vae_noise", seed)),
      order_rng(seed_from_key("vae_order", seed));
  mlp_init(m.shape.encoder, m.params.data(), init);
  mlp_init(m.shape.decoder, m.params.data() + m.shape.encoder.param_count(), init);

  const int B = h.vae.batch, in = d.input_dim, L = h.embedding_dim;
  const int64_t T = d.count;
  std::vector<float> grad(m.params.size()), x(size_t(B) * in), eps(size_t(B) * L);
  AdamState adam(m.params.size());
  VaeWorkspace<float> ws;
  m.loss_curve = run_epochs(T, h.vae.epochs, B, order_rng, [&](const int32_t* rows, int b) {
    for (int i = 0; i < b; ++i)
      std::copy(d.input(rows[i]), d.input(rows[i]) + in, x.begin() + size_t(i) * in);
    for (int i = 0; i < b * L; ++i) eps[i] = float(noise.normal());
    std::fill(grad.begin(), grad.end(), 0.f);
    const float loss = vae_loss_and_grad(m.shape, m.params.data(), x.data(), b, eps.data(),
                                         float(h.vae_kl_weight), grad.data(), ws, nullptr, threads);
    adam_step(h.vae.adam, adam, m.params.data(), grad.data(), m.params.size());
    m.train_flops += 3 * (m.shape.encoder.forward_flops(b) + m.shape.decoder.forward_flops(b));
    return loss;
  });
  require_finite(m.loss_curve, "VAE loss");
  require_finite(m.params, "VAE weights");
  return m;
}

Representation vae_mean_encoder(const VaeModel& vae) {
  const MlpShape& enc = vae.shape.encoder;
  Representation r;
  r.shape = enc;
  r.shape.widths.back() = vae.shape.latent;
  const int last = enc.layers() - 1, hid = enc.widths[last], L = vae.shape.latent;
  r.params.assign(vae.params.begin(), vae.params.begin() + enc.weight_offset(last));
  // Last layer: W [2L, hid] keeps rows [0, L) (the μ half), b [2L] keeps [0, L).
  const float* W = vae.params.data() + enc.weight_offset(last);
  const float* b = vae.params.data() + enc.bias_offset(last);
  r.params.insert(r.params.end(), W, W + size_t(L) * hid);
  r.params.insert(r.params.end(), b, b + L);
  r.method = Method::vae;
  r.loss_curve = vae.loss_curve;
  r.train_flops = vae.train_flops;
  return r;
}

}  // namespace sirl
