// Train one representation φ by any of the paper's methods (plain function over plain data:
// no global state, the call owns its workspace, single-threaded unless `threads` says otherwise).
#pragma once
#include <cstdint>

#include "datasets/dataset.h"
#include "datasets/query_bundle.h"
#include "engine/checkpoint.h"
#include "engine/execution.h"
#include "engine/hyperparams.h"
#include "engine/representation.h"
#include "engine/train_vae.h"

namespace sirl {

struct MethodConfig {
  Method method = Method::sirl;
  int64_t queries = 0;  // N: similarity triplets (SIRL) or preference pairs (the Pref methods)
  bool vae_pretrain = false;  // start φ from the VAE encoder's mean head
  Hyper hyper;
  // SIRL: end training where it reaches a fixed point (engine/train_sirl.cpp; the same weights and
  // curve as running every epoch). false runs every epoch (the tests' reference).
  bool skip_fixed_point = true;
};

// - sirl:        φ trained on the first N triplets of bundle.similarity (symmetric triplet loss).
// - multipref10 / multipref50 / singlepref: shared φ + one linear reward head per human, trained
//   on N preference pairs of the matching bundle set, N/K for each of the K humans.
// - vae:         the encoder mean of `vae` (required).
// - random:      φ at its seeded PyTorch-default initialisation.
// `vae` is required when method == vae or vae_pretrain; φ's random initialisation comes from
// `seed` (the same seed gives Random and the untrained start of SIRL the same weights).
// Throws std::invalid_argument on bad configs and std::runtime_error if training diverges.
Representation train_representation(const Dataset& d, const QueryBundle& bundle,
                                    const MethodConfig& cfg, uint64_t seed,
                                    const VaeModel* vae = nullptr, const Execution& ex = {});

}  // namespace sirl
