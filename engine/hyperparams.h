// The paper's training hyper-parameters (Appendix B–C; docs/ARCHITECTURE.md §4), one set per
// environment. Every value is overridable by name ("sirl.epochs", "tpa.lr", …) so profiles can
// change any of them, and every run records the full set it used (describe()).
#pragma once
#include <string>
#include <vector>

#include "datasets/hyper_value.h"
#include "engine/convergence.h"
#include "kernels/adam.h"

namespace sirl {

struct TrainSchedule {
  int epochs = 1;
  int batch = 32;
  AdamConfig adam;
};

// The most hidden layers a network may list, checked before anything is sized from it: far above
// any network of the paper (two), far below a list that would exhaust memory in planning. (A
// width is not bounded here: a network too big for one machine is still a valid profile, and
// `sirl run` refuses it on a machine without the memory.)
inline constexpr size_t kMaxHiddenLayers = 64;

struct Hyper {
  // φ: input → hidden… → embedding_dim. The paper: ReLU after every hidden layer; its lineage
  // code leaves the embedding layer linear (our default), switchable with phi_relu_output.
  std::vector<int> phi_hidden{128, 128};
  int embedding_dim = 6;
  bool phi_relu_output = false;
  TrainSchedule sirl{3000, 64, {0.004, 0.99999}};
  double triplet_margin = 1.0;  // the paper does not state α; PyTorch's TripletMarginLoss default
  TrainSchedule vae{2000, 32, {0.01, 0.99999}};
  double vae_kl_weight = 0.01;
  // The ELBO's form (the paper says only "a standard variational reconstruction loss", λ = 0.01):
  // "sum" (default, Kingma & Welling): squared error summed over the input's dimensions and KL
  // summed over the latent dimensions, both averaged over the batch. "mean": the squared error
  // averaged over batch × inputs (a KL weight in effect `inputs` times larger; collapses φ).
  std::string vae_elbo = "sum";
  // φ = the encoder's mean μ, expressed in the prior's units: standardised per latent over Ξ
  // (folded into the last layer, so φ stays an MLP on raw inputs). With λ = 0.01 the prior barely
  // bounds μ's scale (measured on JacoRobot: std 1–3000 per latent), and the TPA head's L2 penalty
  // on predicted rewards then swamps its loss: heads on it did not even fit their training pairs.
  bool vae_standardize = true;
  TrainSchedule pref{5000, 32, {0.01, 1.0}};  // MultiPref-K and SinglePref
  double pref_l2 = 10;
  // When a preference φ's training ends: "fixed" runs pref.epochs (the paper's protocol);
  // "converged" ends it at the first epoch e >= pref.stop_min_epochs at which its training loss
  // (shared φ and its K heads) satisfies check_convergence at pref.stop_rel_tol; pref.epochs is the
  // cap. Its test is written down in docs/stopping-rule.md, before any run.
  std::string pref_stop = "fixed";
  int pref_stop_min_epochs = 500;
  double pref_stop_rel_tol = 0.01;
  TrainSchedule tpa{500, 64, {0.001, 1.0}};  // the TPA reward heads
  std::vector<int> tpa_hidden{128, 128};
  double tpa_l2 = 10;
  // When a reward head stops (engine/convergence.h, StopRule): "fixed" runs tpa.epochs (the
  // paper's protocol); "converged" stops each head once its loss has converged, at the earliest
  // after tpa.stop_min_epochs, by check_convergence at tpa.stop_rel_tol (unfrozen cells) or
  // tpa.stop_frozen_rel_tol (frozen cells); tpa.epochs is the cap. "converged-unfrozen": the rule
  // for unfrozen cells only, frozen cells' heads run every epoch. Two tolerances because on
  // JacoRobot the frozen heads' loss still falls slowly where the unfrozen heads' has flattened,
  // so a rule for frozen heads needs a tighter one; no tolerance tried kept SIRL's frozen TPA at
  // the paper's over M = 10-190 (docs/stopping-rule.md).
  std::string tpa_stop = "fixed";
  int tpa_stop_min_epochs = 100;
  double tpa_stop_rel_tol = 0.01;
  double tpa_stop_frozen_rel_tol = 0.01;
  // Above 0, a shadow rule in cells whose heads run every epoch: each head is also scored at
  // the first epoch the "converged" rule at this tolerance (minimum tpa.stop_min_epochs) would
  // have stopped it, and trains on. One run at the paper's epochs then holds both sides of an
  // equivalence test of that rule (TpaResult::shadow_*). 0 (the default): no shadow.
  double tpa_shadow_rel_tol = 0;
  // "fp32" (the paper's) or "bf16": every network's matrix products in bf16 with fp32
  // accumulation, master weights and Adam state in fp32 (MlpShape::bf16_products).
  std::string precision = "fp32";
};

// Throws std::invalid_argument unless precision is "fp32" or "bf16".
void validate_precision(const std::string& precision);

// Whether h asks for bf16 matrix products.
inline bool bf16_products(const Hyper& h) {
  return h.precision == "bf16";
}

// The stopping rule that h.tpa_stop* give a cell's reward heads (frozen φ or not).
StopRule tpa_stop_rule(const Hyper& h, bool frozen);
// The shadow rule of h.tpa_shadow_rel_tol for a cell: "converged" at that tolerance and
// tpa.stop_min_epochs where the cell's heads run every epoch; off (not converged) elsewhere.
StopRule tpa_shadow_rule(const Hyper& h, bool frozen);

// The paper's values for a registered environment (datasets/environments.h: the engine's
// defaults plus the environment's HyperDefault list); throws std::invalid_argument for an unknown
// name.
Hyper paper_hyper(const std::string& env);

// Sets one value by its dotted name (int64_t{3000}, 0.004, std::vector<int>{128, 128}, true).
// Throws std::invalid_argument naming the key and what was expected: an integer key takes an
// integer, a number key an integer or a number, a widths key one width or a list of them.
void set_hyper(Hyper& h, const std::string& key, const HyperValue& value);
// The value of a key (set_hyper(h2, key, hyper_value(h, key)) copies it exactly).
HyperValue hyper_value(const Hyper& h, const std::string& key);
// A value's canonical text: "3000", "0.0040000000000000001" (17 digits), "128,128", "true", a
// word as it is. Hyper-parameter points are named by it (their task keys).
std::string hyper_value_text(const HyperValue& v);

// What a key's value is, so a profile can refuse a value of the wrong kind (30.0 or [30] for an
// epoch count) before it becomes text: integer, number (integer or real), boolean, a list of
// integers (widths) or a word. Throws std::invalid_argument for an unknown key.
enum class HyperType { integer, number, boolean, integer_list, word };
HyperType hyper_type(const std::string& key);
const char* hyper_type_name(HyperType t);

// Every key, in a fixed order (what set_hyper accepts).
std::vector<std::string> hyper_keys();

// "key = value" lines, one per key, in hyper_keys() order: what a run records.
std::string describe(const Hyper& h);

// Throws std::invalid_argument on epochs/batch < 1, lr ≤ 0, decay ∉ (0,1], widths < 1, …
void validate(const Hyper& h);

}  // namespace sirl
