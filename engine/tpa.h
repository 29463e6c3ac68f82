// Test Preference Accuracy (paper §4.3): how well φ supports learning new rewards from M
// preference pairs. One reward head per test reward; the heads of a cell train one after another,
// each a stretch of steps in a row (engine/epochs.h, run_model_epochs).
#pragma once
#include <cstdint>
#include <vector>

#include "datasets/dataset.h"
#include "datasets/queries.h"
#include "engine/checkpoint.h"
#include "engine/epochs.h"
#include "engine/execution.h"
#include "engine/hyperparams.h"
#include "engine/representation.h"

namespace sirl {

struct TpaConfig {
  int64_t M = 10;      // training pairs per test reward (the first M of its 80 % split)
  bool frozen = true;  // frozen: φ fixed, the head learns on φ(ξ); unfrozen: each head fine-tunes
                       // its own copy of φ (φ + head trained as one network)
  Hyper hyper;  // tpa.* (epochs, batch, Adam, hidden widths, L2)
};

struct TpaResult {
  std::vector<double> accuracy;        // [R] held-out accuracy per test reward
  std::vector<double> train_accuracy;  // [R] accuracy on the head's own M training pairs
  double mean = 0, stddev = 0;         // TPA = mean over rewards; stddev over rewards (n − 1)
  int epochs = 0;                      // the schedule's epochs (tpa.epochs): the cap on every head
  std::vector<int> head_epochs;        // [R] epochs each head trained (< epochs: stopped, tpa.stop)
  std::vector<float> loss_curves;      // [R, epochs] mean training loss per epoch, per head; NaN
                                       // after a head stopped
  std::vector<float> phi_drift;        // [R] max |Δ| of the head's copy of φ (0 when frozen)
  double train_flops = 0;              // FLOPs the heads' training executed
  double protocol_flops = 0;  // FLOPs of every head's full schedule (== train_flops when fixed)
  // The shadow rule (tpa.shadow_rel_tol, where the heads run every epoch; empty otherwise): the
  // epoch each head would have stopped at under it (the cap when it never would) and its
  // held-out accuracy there: bit for bit a run stopped by that rule.
  std::vector<int> shadow_epochs;       // [R]
  std::vector<double> shadow_accuracy;  // [R]
  double shadow_mean = 0;               // the mean of shadow_accuracy: that run's TPA
};

// The network each head trains: frozen → the head alone on φ(ξ) (embedding → tpa_hidden… → 1);
// unfrozen → φ and the head stacked, φ's embedding layer kept linear as in φ itself.
MlpShape tpa_network(const MlpShape& phi, const Hyper& h, bool frozen);

// sets[r] holds reward r's labelled pairs: rows [0, train) for training (the first M are
// used), rows [train, count) held out. Head initialisation and batch order come from streams
// of `seed` per reward, so frozen and unfrozen cells of one seed start from the same heads.
// Throws std::invalid_argument if M is outside [1, train] or a held-out split is empty, and
// std::runtime_error if training diverges.
TpaResult evaluate_tpa(const Representation& rep, const Dataset& d, const std::vector<TpaSet>& sets,
                       const TpaConfig& cfg, uint64_t seed, const Execution& ex = {});

}  // namespace sirl
