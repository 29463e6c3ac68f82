// The paper's symmetric triplet loss (SIRL eq. 2) on squared L2 distances.
#pragma once

namespace sirl {

// emb [3B, d]: rows [0,B) = φ(ξ_P1), [B,2B) = φ(ξ_P2), [2B,3B) = φ(ξ_N).
// d(a,b) = ‖a − b‖²;  L = (1/B) Σ_i  max(d(P1,P2) − d(P1,N) + α, 0) + max(d(P2,P1) − d(P2,N) + α,
// 0) (the paper writes a sum; we take the batch mean, as PyTorch losses do, so the learning rate
// does not depend on the batch size). Writes ∂L/∂emb into demb [3B, d] when not null.
template <typename T>
T symmetric_triplet_loss(const T* emb, int B, int d, T margin, T* demb);

// The largest hinge of the batch, max over i of max(h1_i, h2_i) with h = d(P,P') − d(P,N) + α:
// ≤ 0 means no triplet contributes to the loss or its gradient (both exactly 0).
template <typename T>
T triplet_max_hinge(const T* emb, int B, int d, T margin);

// Fraction of triplets whose embedding already ranks them right: d(P1,P2) < min(d(P1,N), d(P2,N)).
template <typename T>
double triplet_accuracy(const T* emb, int B, int d);

}  // namespace sirl
