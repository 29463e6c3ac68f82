#include "kernels/vae.h"

#include <algorithm>
#include <cmath>
#include <functional>

namespace sirl {

namespace {
// log σ² is clamped to [−30, 20] before use: σ = exp(½ log σ²) overflows float (and the loss
// turns NaN) when a large learning rate meets large inputs (JacoRobot's raw 2037-d states at the
// paper's lr 0.01). Inside the range the loss and gradient are exactly the textbook ones;
// outside it only the KL's gradient passes (see below).
template <typename T>
T clamp_logvar(T lv) {
  return std::min(std::max(lv, T(-30)), T(20));
}
}  // namespace

VaeShape make_vae_shape(int in, const std::vector<int>& hidden, int latent) {
  VaeShape s;
  s.latent = latent;
  s.encoder.widths = {in};
  s.encoder.widths.insert(s.encoder.widths.end(), hidden.begin(), hidden.end());
  s.encoder.widths.push_back(2 * latent);
  s.decoder.widths = {latent};
  s.decoder.widths.insert(s.decoder.widths.end(), hidden.rbegin(), hidden.rend());
  s.decoder.widths.push_back(in);
  validate(s.encoder);
  validate(s.decoder);
  return s;
}

namespace {

// The loss and its backward pass, shared by both entry points. `backward_decoder(d_recon, d_z)`
// runs the decoder's backward pass from ∂L/∂x̂ and must write ∂L/∂z; `backward_encoder(d_out)`
// runs the encoder's from ∂L/∂(μ | log σ²). Both are skipped when `grad` is false. Each reads
// only its own network's weights, so the decoder's may already be updated when the encoder's
// pass runs. The passes are std::functions, not template parameters, and the body is never
// inlined or specialised (noipa), so that the loss's own arithmetic is compiled once per scalar
// type: specialised for the fused caller (which passes grad = true), GCC vectorised and fused
// multiply-adds differently and the gradients differed in the last bit.
#if defined(__clang__)  // clang has no noipa (and does not clone on constant arguments)
#define SIRL_NOT_SPECIALISED [[gnu::noinline]]
#else
#define SIRL_NOT_SPECIALISED [[gnu::noipa]]
#endif
template <typename T>
SIRL_NOT_SPECIALISED T vae_loss(const VaeShape& s, const T* params, const T* x, int B, const T* eps,
                                T kl_weight, VaeElbo elbo, bool grad,
                                const std::function<void(const T*, T*)>& backward_decoder,
                                const std::function<void(const T*)>& backward_encoder,
                                VaeWorkspace<T>& ws, VaeLossParts* parts, int threads) {
  const int in = s.encoder.in(), d = s.latent;
  const T* enc_p = params;
  const T* dec_p = params + s.encoder.param_count();
  // Encode: h [B, 2d] = (μ | log σ²); sample z [B, d].
  mlp_forward(s.encoder, enc_p, x, B, ws.enc, threads);
  const T* h = ws.enc.output();
  ws.z.resize(size_t(B) * d);
  for (int i = 0; i < B; ++i)
    for (int k = 0; k < d; ++k) {
      const T mu = h[size_t(i) * 2 * d + k], lv = clamp_logvar(h[size_t(i) * 2 * d + d + k]);
      ws.z[size_t(i) * d + k] = mu + std::exp(T(0.5) * lv) * eps[size_t(i) * d + k];
    }
  // Decode: x̂ [B, in].
  mlp_forward(s.decoder, dec_p, ws.z.data(), B, ws.dec, threads);
  const T* xr = ws.dec.output();
  T rec = 0, kl = 0;
  const T inv_b = T(1) / T(B);
  const T inv_n = elbo == VaeElbo::sum_over_inputs ? inv_b : T(1) / (T(B) * in);
  ws.d_recon.resize(size_t(B) * in);
  for (size_t j = 0; j < size_t(B) * in; ++j) {
    const T e = xr[j] - x[j];
    rec += e * e;
    ws.d_recon[j] = 2 * e * inv_n;
  }
  const T sq_error = rec / (T(B) * in);
  rec *= inv_n;
  if (parts) parts->kl_per_dim.assign(d, 0.0);
  ws.d_z.resize(size_t(B) * d);
  if (grad) backward_decoder(ws.d_recon.data(), ws.d_z.data());
  ws.d_enc_out.resize(size_t(B) * 2 * d);
  for (int i = 0; i < B; ++i)
    for (int k = 0; k < d; ++k) {
      const size_t im = size_t(i) * 2 * d + k, il = im + d, iz = size_t(i) * d + k;
      const T mu = h[im], lv = clamp_logvar(h[il]), sd = std::exp(T(0.5) * lv);
      const T kl_ik = T(-0.5) * (1 + lv - mu * mu - sd * sd);
      kl += kl_ik;
      if (parts) parts->kl_per_dim[k] += double(kl_ik) / B;
      if (!grad) continue;
      // through z = μ + σ·ε, plus the KL term's own gradient
      ws.d_enc_out[im] = ws.d_z[iz] + kl_weight * mu * inv_b;
      // The sample path has no gradient outside the clamp (as torch.clamp), but the KL's does
      // (straight through): with a zero gradient there, a log σ² that once overshot below −30
      // stayed there for good (σ ≈ 3e−7: a deterministic auto-encoder whose KL could not act),
      // as measured on JacoRobot at lr 0.01. The KL pulls it back into range.
      ws.d_enc_out[il] = (lv == h[il] ? ws.d_z[iz] * eps[iz] * T(0.5) * sd : T(0)) +
                         kl_weight * T(0.5) * (sd * sd - 1) * inv_b;
    }
  kl *= inv_b;
  if (grad) backward_encoder(ws.d_enc_out.data());
  if (parts) {
    parts->reconstruction = double(rec);
    parts->squared_error = double(sq_error);
    parts->kl = double(kl);
  }
  return rec + kl_weight * kl;
}

}  // namespace

template <typename T>
T vae_loss_and_grad(const VaeShape& s, const T* params, const T* x, int B, const T* eps,
                    T kl_weight, VaeElbo elbo, T* dparams, VaeWorkspace<T>& ws, VaeLossParts* parts,
                    int threads) {
  const size_t E = s.encoder.param_count();
  return vae_loss<T>(
      s, params, x, B, eps, kl_weight, elbo, dparams != nullptr,
      [&](const T* d_recon, T* d_z) {
        mlp_backward(s.decoder, params + E, ws.dec, d_recon, dparams + E, d_z, threads);
      },
      [&](const T* d_out) {
        mlp_backward(s.encoder, params, ws.enc, d_out, dparams, static_cast<T*>(nullptr), threads);
      },
      ws, parts, threads);
}

float vae_loss_and_adam_step(const VaeShape& s, float* params, const float* x, int B,
                             const float* eps, float kl_weight, VaeElbo elbo,
                             const AdamStepScalars& step, float* m, float* v,
                             VaeWorkspace<float>& ws, VaeLossParts* parts, int threads) {
  const size_t E = s.encoder.param_count();
  return vae_loss<float>(
      s, params, x, B, eps, kl_weight, elbo, true,
      [&](const float* d_recon, float* d_z) {
        mlp_backward_adam(s.decoder, params + E, ws.dec, d_recon, step, m + E, v + E, threads, d_z);
      },
      [&](const float* d_out) {
        mlp_backward_adam(s.encoder, params, ws.enc, d_out, step, m, v, threads);
      },
      ws, parts, threads);
}

template float vae_loss_and_grad<float>(const VaeShape&, const float*, const float*, int,
                                        const float*, float, VaeElbo, float*, VaeWorkspace<float>&,
                                        VaeLossParts*, int);
template double vae_loss_and_grad<double>(const VaeShape&, const double*, const double*, int,
                                          const double*, double, VaeElbo, double*,
                                          VaeWorkspace<double>&, VaeLossParts*, int);

}  // namespace sirl
