// The paper's unsupervised baseline and pre-training: a VAE over every trajectory of Ξ.
#pragma once
#include <cstdint>
#include <vector>

#include "datasets/dataset.h"
#include "engine/hyperparams.h"
#include "engine/representation.h"
#include "kernels/vae.h"

namespace sirl {

struct VaeModel {
  VaeShape shape;  // encoder in → phi_hidden… → 2·d, decoder d → …reversed… → in
  std::vector<float> params;      // [encoder | decoder]
  std::vector<float> loss_curve;  // mean ELBO loss per epoch
  double train_flops = 0;
};

// Trains on all d.count trajectories with h.vae (epochs, batch, Adam) and h.vae_kl_weight; the
// initial weights and the reparameterisation noise come from streams of `seed`.
// Throws std::runtime_error if the loss or weights become non-finite.
VaeModel train_vae(const Dataset& d, const Hyper& h, uint64_t seed, int threads = 1);

// φ = the encoder's mean head: the encoder with its last layer cut to the first d outputs (μ).
Representation vae_mean_encoder(const VaeModel& vae);

}  // namespace sirl
