// The epochs a training is expected to execute, for the cost model (`sirl plan`): the schedule's,
// except where the engine ends a training early by rule:
// - SIRL's exact skip (engine/train_sirl.cpp): a training stops at its fixed point;
// - reward heads under tpa.stop = "converged" (engine/convergence.h, StopRule);
// - preference φ under pref.stop = "converged" (the same rule on φ's training loss).
// Where that happens depends on the data, so these are measured medians (the tables in
// expected_epochs.cpp say where from), interpolated in the number of queries and clamped to the
// schedule. An environment or setting without a measurement is expected to run every epoch.
#pragma once
#include <cstdint>
#include <string>

#include "engine/hyperparams.h"

namespace sirl {

// Epochs a SIRL φ training (N triplets; from the VAE's encoder when vae_pretrain) is expected to
// run before its exact skip, at most h.sirl.epochs.
double expected_sirl_epochs(const std::string& env, int64_t N, bool vae_pretrain, const Hyper& h);

// Epochs a TPA cell's reward heads are expected to run on average, at most h.tpa.epochs:
// all of them under tpa.stop = "fixed".
double expected_head_epochs(const std::string& env, bool frozen, int64_t M, const Hyper& h);

// Epochs a preference φ of `method` ("singlepref", "multipref10", …; N pairs; from the VAE's
// encoder when vae_pretrain) is expected to run, at most h.pref.epochs: all of them under
// pref.stop = "fixed".
double expected_pref_epochs(const std::string& env, const std::string& method, int64_t N,
                            bool vae_pretrain, const Hyper& h);

}  // namespace sirl
