#include "engine/train_vae.h"

#include <algorithm>
#include <cmath>

#include "engine/epochs.h"
#include "kernels/adam.h"
#include "kernels/rng.h"

namespace sirl {

VaeElbo vae_elbo_form(const Hyper& h) {
  return h.vae_elbo == "mean" ? VaeElbo::mean_over_inputs : VaeElbo::sum_over_inputs;
}

namespace {
// KL per latent dimension and reconstruction error over all of Ξ, with z = μ (ε = 0).
void measure_posterior(const Dataset& d, VaeModel& m, int threads) {
  constexpr int kChunk = 256;
  const int L = m.shape.latent;
  std::vector<float> eps(size_t(kChunk) * L, 0.f);
  VaeWorkspace<float> ws;
  VaeLossParts parts;
  std::vector<double> kl(L, 0.0), mu_sum(L, 0.0), mu_sq(L, 0.0);
  double sq = 0;
  for (int64_t i0 = 0; i0 < d.count; i0 += kChunk) {
    const int b = int(std::min<int64_t>(kChunk, d.count - i0));
    vae_loss_and_grad(m.shape, m.params.data(), d.input(i0), b, eps.data(), 0.f, m.elbo,
                      static_cast<float*>(nullptr), ws, &parts, threads);
    for (int k = 0; k < L; ++k) kl[k] += parts.kl_per_dim[k] * b;
    sq += parts.squared_error * b;
    const float* h = ws.enc.output();  // [b, 2L]: μ | log σ²
    for (int i = 0; i < b; ++i)
      for (int k = 0; k < L; ++k) {
        const double mu = h[size_t(i) * 2 * L + k];
        mu_sum[k] += mu;
        mu_sq[k] += mu * mu;
      }
  }
  const double n = double(d.count);
  m.kl_per_dim.resize(L);
  m.latent_mean.resize(L);
  m.latent_std.resize(L);
  for (int k = 0; k < L; ++k) {
    m.kl_per_dim[k] = float(kl[k] / n);
    const double mean = mu_sum[k] / n;
    m.latent_mean[k] = float(mean);
    m.latent_std[k] = float(std::sqrt(std::max(0.0, mu_sq[k] / n - mean * mean)));
  }
  m.reconstruction_mse = sq / n;
}
}  // namespace

VaeModel train_vae(const Dataset& d, const Hyper& h, uint64_t seed, const Execution& ex) {
  const int threads = ex.threads;
  validate(h);
  VaeModel m;
  m.elbo = vae_elbo_form(h);
  m.standardize = h.vae_standardize;
  m.shape = make_vae_shape(d.input_dim, h.phi_hidden, h.embedding_dim);
  m.shape.encoder.bf16_products = m.shape.decoder.bf16_products = bf16_products(h);
  m.params.resize(m.shape.param_count());
  Rng init(seed_from_key("vae_init", seed)), noise(seed_from_key("vae_noise", seed)),
      order_rng(seed_from_key("vae_order", seed));
  mlp_init(m.shape.encoder, m.params.data(), init);
  mlp_init(m.shape.decoder, m.params.data() + m.shape.encoder.param_count(), init);

  const int B = h.vae.batch, in = d.input_dim, L = h.embedding_dim;
  const int64_t T = d.count;
  AlignedVector<float> x(size_t(B) * in), eps(size_t(B) * L);
  AdamState adam(m.params.size());
  VaeWorkspace<float> ws;
  VaeLossParts parts;
  double rec_sum = 0, kl_sum = 0;
  int64_t rows_seen = 0;
  // At an epoch boundary the per-epoch sums are 0 and rows_seen is epochs × T: the weights, Adam,
  // the noise stream, the two curves and the FLOP count are the whole state.
  const ResumableState resume{ex.checkpointer,
                              [&](TrainingSnapshot& snap) {
                                put_adam(snap, "vae", m.params, adam);
                                snap.put_rng("vae/noise", noise);
                                snap.floats["vae/reconstruction_curve"] = m.reconstruction_curve;
                                snap.floats["vae/kl_curve"] = m.kl_curve;
                                snap.numbers["train_flops"] = m.train_flops;
                              },
                              [&](const TrainingSnapshot& snap) {
                                get_adam(snap, "vae", m.params, adam);
                                snap.get_rng("vae/noise", noise);
                                m.reconstruction_curve =
                                    snap.get("vae/reconstruction_curve", size_t(snap.epoch));
                                m.kl_curve = snap.get("vae/kl_curve", size_t(snap.epoch));
                                m.train_flops = snap.number("train_flops");
                                rows_seen = int64_t(snap.epoch) * T;
                              }};
  m.loss_curve = run_epochs(
      T, h.vae.epochs, B, order_rng,
      [&](const int32_t* rows, int b) {
        for (int i = 0; i < b; ++i)
          std::copy(d.input(rows[i]), d.input(rows[i]) + in, x.begin() + size_t(i) * in);
        for (int i = 0; i < b * L; ++i) eps[i] = float(noise.normal());
        // The backward pass updates the weights as it goes (the gradient is never stored).
        const AdamStepScalars step = adam_begin_step(h.vae.adam, adam);
        const float loss = vae_loss_and_adam_step(
            m.shape, m.params.data(), x.data(), b, eps.data(), float(h.vae_kl_weight), m.elbo, step,
            adam.m.data(), adam.v.data(), ws, &parts, threads);
        m.train_flops += m.shape.encoder.train_flops(b) + m.shape.decoder.train_flops(b);
        rec_sum += parts.reconstruction * b;
        kl_sum += parts.kl * b;
        if ((rows_seen += b) % T == 0) {  // the epoch's last batch
          m.reconstruction_curve.push_back(float(rec_sum / double(T)));
          m.kl_curve.push_back(float(kl_sum / double(T)));
          rec_sum = kl_sum = 0;
        }
        return loss;
      },
      &resume);
  require_finite(m.loss_curve, "VAE loss");
  require_finite(m.params, "VAE weights");
  measure_posterior(d, m, threads);
  m.train_flops +=
      m.shape.encoder.forward_flops(int(d.count)) + m.shape.decoder.forward_flops(int(d.count));
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
  if (vae.standardize && int(vae.latent_std.size()) == L) {
    // φ_k = (W_k·h + b_k − mean_k) / std_k: rescale row k of W and b_k (a constant μ_k stays
    // unscaled rather than dividing by 0).
    float* Wphi = r.params.data() + enc.weight_offset(last);
    float* bphi = Wphi + size_t(L) * hid;
    for (int k = 0; k < L; ++k) {
      const float s = vae.latent_std[k] > 1e-12f ? 1.f / vae.latent_std[k] : 1.f;
      for (int j = 0; j < hid; ++j) Wphi[size_t(k) * hid + j] *= s;
      bphi[k] = (bphi[k] - vae.latent_mean[k]) * s;
    }
  }
  r.method = Method::vae;
  r.loss_curve = vae.loss_curve;
  r.train_flops = vae.train_flops;
  return r;
}

}  // namespace sirl
