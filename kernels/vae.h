// Variational auto-encoder loss and gradient (Kingma & Welling), the paper's unsupervised
// pre-training: Gaussian encoder → reparameterised sample → decoder.
//   encoder MLP: in → hidden… → 2·latent   (columns [0,latent) = mean μ, [latent,2·latent) = log
//   σ²) decoder MLP: latent → hidden… → in
// The encoder's mean head has exactly φ's shape (in → hidden… → latent), so SIRL+VAE copies it.
#pragma once
#include <vector>

#include "kernels/mlp.h"

namespace sirl {

struct VaeShape {
  MlpShape encoder, decoder;
  int latent = 0;
  size_t param_count() const { return encoder.param_count() + decoder.param_count(); }
};

// hidden = e.g. {128, 128}: encoder in→128→128→2·latent, decoder latent→128→128→in.
VaeShape make_vae_shape(int in, const std::vector<int>& hidden, int latent);

// How the reconstruction term is scaled.
//   sum_over_inputs (the standard ELBO, Kingma & Welling): (1/B) Σ_i Σ_j (x̂_ij − x_ij)²
//   mean_over_inputs: (1/(B·in)) Σ_i Σ_j (x̂_ij − x_ij)² — against the same KL this weighs the
//   KL `in` times more (≈2000× for JacoRobot's 2037 inputs).
// The KL is in both forms (1/B) Σ_i Σ_k KL_ik, summed over the latent dimensions.
enum class VaeElbo { sum_over_inputs, mean_over_inputs };

struct VaeLossParts {
  double reconstruction = 0;       // the reconstruction term as the form defines it
  double squared_error = 0;        // mean over batch·in of (x̂ − x)² (form-independent)
  double kl = 0;                   // mean over batch of Σ_k KL(q(z_k|x) ‖ N(0, 1))
  std::vector<double> kl_per_dim;  // [latent] mean over batch of KL_k
};

template <typename T>
struct VaeWorkspace {
  MlpTape<T> enc, dec;
  AlignedVector<T> z, d_recon, d_z, d_enc_out;
};

// params = [encoder params | decoder params]; x [B, in]; eps [B, latent] standard-normal noise
// (drawn by the caller so the step is a pure function). z = μ + exp(½ log σ²)·eps, with log σ²
// clamped to [−30, 20] so σ cannot overflow; outside the range the sample path has no gradient
// (as torch.clamp) but the KL's gradient passes straight through, so a log σ² that overshot
// is pulled back instead of sticking at the bound.
//   L = reconstruction (see VaeElbo)  +  λ · (1/B) Σ_i −½ Σ_k (1 + log σ² − μ² − σ²)
// Adds ∂L/∂params into dparams (zero it first; may be null). Returns L.
template <typename T>
T vae_loss_and_grad(const VaeShape& shape, const T* params, const T* x, int B, const T* eps,
                    T kl_weight, VaeElbo elbo, T* dparams, VaeWorkspace<T>& ws,
                    VaeLossParts* parts = nullptr, int threads = 1);

// The same loss, and Adam's step on params (scalars of adam_begin_step; moments m, v [P]) fused
// into the backward pass: each network's weights are updated as their gradients appear
// (mlp_backward_adam; the decoder's before the encoder's pass, which reads none of them), so the
// gradient [P] is never stored. The same bits as vae_loss_and_grad into a zeroed gradient
// followed by adam_apply over [P] (a test checks it).
float vae_loss_and_adam_step(const VaeShape& shape, float* params, const float* x, int B,
                             const float* eps, float kl_weight, VaeElbo elbo,
                             const AdamStepScalars& step, float* m, float* v,
                             VaeWorkspace<float>& ws, VaeLossParts* parts = nullptr,
                             int threads = 1);

}  // namespace sirl
