// One optimizer step of each training objective: forward, loss, backward, Adam.
// A Trainer is the mutable workspace of one training run (MuJoCo's mjData in spirit): it owns
// the parameters, optimizer moments and activation buffers (no gradient: every step fuses its
// Adam update into the backward pass); nothing is global.
#pragma once
#include <cstdint>
#include <vector>

#include "kernels/adam.h"
#include "kernels/mlp.h"

namespace sirl {

struct Trainer {
  MlpShape shape;
  AdamConfig adam_cfg;
  std::vector<float> params;  // [P] (+ any trailing parameters a step owns, e.g. heads)
  AdamState adam;
  MlpTape<float> tape;
  AlignedVector<float> batch_x, d_out;  // gathered inputs, ∂L/∂output

  Trainer(MlpShape s, AdamConfig cfg, std::vector<float> initial_params);
};

// Stacks query rows role by role: idx [B, roles] row indices into X [T, in] →
// out [roles·B, in] with out[r·B + i] = X[idx[i·roles + r]] (P1 | P2 | N for triplets, A | B for
// pairs).
void gather_by_role(const float* X, int in, const int32_t* idx, int B, int roles, float* out);

// Symmetric triplet step on B triplets given as row indices into X:
//   triplets [B, 3] = (P1, P2, N); the network sees [3B, in] stacked P1 | P2 | N.
// Returns the loss before the update.
float triplet_train_step(Trainer& t, const float* X, const int32_t* triplets, int B, float margin,
                         int threads = 1);

// Bradley–Terry step for a reward network R: pairs [B, 2] = (A, B) row indices into X,
// label [B] (1 = A preferred). Returns the loss before the update.
float preference_train_step(Trainer& t, const float* X, const int32_t* pairs, const float* label,
                            int B, float l2_weight, int threads = 1);

// Multi-task preference step (MultiPref-K, SinglePref): a shared φ with K linear reward heads,
// r_k(ξ) = w_k · φ(ξ) + c_k. t.params = [φ params (t.shape) | K × (w_k [d], c_k)].
// pairs [B, 2] row indices into X, label [B], human [B] ∈ [0, K) picks each pair's head.
// Returns the loss before the update.
float multihead_preference_train_step(Trainer& t, int K, const float* X, const int32_t* pairs,
                                      const float* label, const int32_t* human, int B,
                                      float l2_weight, int threads = 1);

// M reward heads of one shape trained side by side (the 20 TPA heads of a cell, or seeds),
// each with its own weights, its own pairs and its own labels; one Adam over all M·P values.
struct BatchedTrainer {
  // One model's activations and scratch: separate per model, so models can step on different
  // threads, and at different steps (run_model_epochs).
  struct ModelWork {
    MlpTape<float> tape;
    AlignedVector<float> x, d_out;  // gathered inputs [roles·B, in], ∂L/∂output [roles·B, out]
  };
  MlpShape shape;
  int models = 0;
  AdamConfig adam_cfg;
  std::vector<float> params;    // [M, P]; the gradient is never stored (mlp_backward_adam)
  AdamState adam;               // moments [M, P]; step = the steps every model has taken
  std::vector<ModelWork> work;  // [M]
  std::vector<float> losses;    // [M] loss of each head at the last step

  BatchedTrainer(MlpShape s, int models, AdamConfig cfg, std::vector<float> initial_params);
};

// Model m's step alone, as Adam's step `step` (adam_step_scalars; a model's steps are counted by
// its epoch loop, engine/epochs.h): gather, forward pass, loss and backward pass with its Adam
// update back to back on the calling thread, so a head's weights, moments and activations stay in
// cache from its forward to its backward pass. Sets and returns t.losses[m]; t.adam.step is the
// caller's to keep. Calls for different models may run at once on different threads; each model's
// bits are those of a Trainer of its own taking the same steps.
// Preference (Bradley–Terry) heads: pairs [B, 2] row indices into X [T, in], label [B].
float preference_train_step_of_model(BatchedTrainer& t, int m, const AdamStepScalars& step,
                                     const float* X, const int32_t* pairs, const float* label,
                                     int B, float l2_weight);
// An ensemble of φ: triplets [B, 3] = (P1, P2, N) row indices into X [T, in].
float triplet_train_step_of_model(BatchedTrainer& t, int m, const AdamStepScalars& step,
                                  const float* X, const int32_t* triplets, int B, float margin);

// FLOPs of one epoch over n examples in batches of `batch`, each example `roles` rows through s
// (3 for triplets, 2 for pairs), for `copies` models: Σ over the epoch's batches of
// copies · s.train_flops(roles · b), added batch by batch onto `total` (a running count keeps
// the bits of one that added each step as it ran).
double epoch_train_flops(const MlpShape& s, int64_t n, int batch, int roles, int copies = 1,
                         double total = 0);

}  // namespace sirl
