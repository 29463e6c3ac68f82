// One optimizer step of each training objective: forward, loss, backward, Adam.
// A Trainer is the mutable workspace of a training run of R ≥ 1 models (MuJoCo's mjData in
// spirit): it owns the parameters, optimizer moments and activation buffers (no gradient: every
// step fuses its Adam update into the backward pass); nothing is global.
#pragma once
#include <cstdint>
#include <vector>

#include "kernels/adam.h"
#include "kernels/mlp.h"

namespace sirl {

// R ≥ 1 models of one network shape trained side by side, each with its own weights, its own
// examples and its own Adam moments: one training (R = 1), the 20 reward heads of a TPA cell, an
// active ensemble. A model's parameters are the network's P, then any trailing ones its step owns
// (MultiPref's linear heads). The step number is the caller's: the epoch loop derives it from the
// epoch and batch (engine/epochs.h), so every step takes its AdamStepScalars as an argument.
struct Trainer {
  // One model's activations and scratch: separate per model, so models can step on different
  // threads, and at different steps (run_model_epochs).
  struct ModelWork {
    MlpTape<float> tape;
    AlignedVector<float> x, d_out;  // gathered inputs [roles·B, in], ∂L/∂output [roles·B, out]
  };
  MlpShape shape;
  int models = 1;
  size_t stride = 0;  // floats per model: P, then its trailing parameters
  AdamConfig adam_cfg;
  std::vector<float> params;    // [R, stride]; the gradient is never stored (mlp_backward_adam)
  AdamState adam;               // moments [R, stride]
  std::vector<ModelWork> work;  // [R]
  std::vector<float> losses;    // [R] each model's loss at its last step

  // initial [R · stride]: R models' parameters back to back, each at least the network's P.
  // Throws std::invalid_argument otherwise.
  Trainer(MlpShape s, AdamConfig cfg, std::vector<float> initial, int models = 1);
  float* model_params(int m) { return params.data() + size_t(m) * stride; }
};

// Stacks query rows role by role: idx [B, roles] row indices into X [T, in] →
// out [roles·B, in] with out[r·B + i] = X[idx[i·roles + r]] (P1 | P2 | N for triplets, A | B for
// pairs).
void gather_by_role(const float* X, int in, const int32_t* idx, int B, int roles, float* out);

// Model m's step as Adam's step `step` (adam_step_scalars): gather, forward pass, loss and backward
// pass with its Adam update back to back, its products on `threads` threads. A model's weights,
// moments and activations then stay in cache from its forward to its backward pass. Sets and
// returns t.losses[m], the loss before the update. Calls for different models may run at once on
// different threads; a model's bits are those of a one-model Trainer taking the same steps, for
// any thread count. Trailing parameters a step does not use get the zero gradient they have.
//
// Symmetric triplet loss: triplets [B, 3] = (P1, P2, N) row indices into X [T, in]; the network
// sees [3B, in] stacked P1 | P2 | N.
float triplet_train_step(Trainer& t, int m, const AdamStepScalars& step, const float* X,
                         const int32_t* triplets, int B, float margin, int threads = 1);
// Bradley–Terry loss of a reward network R: pairs [B, 2] = (A, B) row indices into X, label [B]
// (1 = A preferred).
float preference_train_step(Trainer& t, int m, const AdamStepScalars& step, const float* X,
                            const int32_t* pairs, const float* label, int B, float l2_weight,
                            int threads = 1);
// Multi-task preference loss (MultiPref-K, SinglePref): a shared φ with K linear reward heads,
// r_k(ξ) = w_k · φ(ξ) + c_k; model m's parameters are [φ (t.shape) | K × (w_k [d], c_k)].
// pairs [B, 2] row indices into X, label [B], human [B] ∈ [0, K) picks each pair's head.
float multihead_preference_train_step(Trainer& t, int m, const AdamStepScalars& step, int K,
                                      const float* X, const int32_t* pairs, const float* label,
                                      const int32_t* human, int B, float l2_weight,
                                      int threads = 1);

// FLOPs of one epoch over n examples in batches of `batch`, each example `roles` rows through s
// (3 for triplets, 2 for pairs), for `copies` models: Σ over the epoch's batches of
// copies · s.train_flops(roles · b), added batch by batch onto `total` (a running count keeps
// the bits of one that added each step as it ran).
double epoch_train_flops(const MlpShape& s, int64_t n, int batch, int roles, int copies = 1,
                         double total = 0);

}  // namespace sirl
