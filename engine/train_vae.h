// The paper's unsupervised baseline and pre-training: a VAE over every trajectory of Ξ.
#pragma once
#include <cstdint>
#include <vector>

#include "datasets/dataset.h"
#include "engine/checkpoint.h"
#include "engine/execution.h"
#include "engine/hyperparams.h"
#include "engine/representation.h"
#include "kernels/vae.h"

namespace sirl {

struct VaeModel {
  VaeShape shape;  // encoder in → phi_hidden… → 2·d, decoder d → …reversed… → in
  std::vector<float> params;  // [encoder | decoder]
  VaeElbo elbo = VaeElbo::sum_over_inputs;
  std::vector<float> loss_curve;            // mean loss per epoch (reconstruction + λ·KL)
  std::vector<float> reconstruction_curve;  // its reconstruction term per epoch
  std::vector<float> kl_curve;              // its KL term (summed over latents) per epoch
  // After training, over all of Ξ with z = μ (no sampling): a latent dimension whose KL is ≈ 0
  // carries no information about the input (posterior collapse).
  std::vector<float> kl_per_dim;  // [latent] mean over Ξ of KL(q(z_k|ξ) ‖ N(0, 1)), nats
  double reconstruction_mse = 0;  // mean over Ξ × inputs of (x̂ − x)²
  // μ's mean and standard deviation over Ξ per latent; vae_mean_encoder folds them into φ when
  // standardize is set (h.vae_standardize at training time).
  std::vector<float> latent_mean, latent_std;
  bool standardize = true;
  double train_flops = 0;
};

// "sum" → sum_over_inputs, "mean" → mean_over_inputs (validate(Hyper) checks the name).
VaeElbo vae_elbo_form(const Hyper& h);

// Trains on all d.count trajectories with h.vae (epochs, batch, Adam) and h.vae_kl_weight; the
// initial weights and the reparameterisation noise come from streams of `seed`.
// Throws std::runtime_error if the loss or weights become non-finite.
VaeModel train_vae(const Dataset& d, const Hyper& h, uint64_t seed, const Execution& ex = {});

// φ = the encoder's mean head: the encoder with its last layer cut to the first d outputs (μ),
// and, when vae.standardize, that layer rescaled so φ_k = (μ_k − mean_k) / std_k over Ξ.
Representation vae_mean_encoder(const VaeModel& vae);

}  // namespace sirl
