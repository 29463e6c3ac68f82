// Bradley–Terry preference loss (SIRL eqs. 3–4) with an L2 penalty on the predicted rewards
// (the paper's stand-in for Christiano et al.'s reward normalisation).
#pragma once

namespace sirl {

// r [2B]: r[i] = R(ξ_A^i), r[B+i] = R(ξ_B^i). label [B] ∈ [0,1]: 1 = A preferred, 0 = B
// preferred, 0.5 = "equally good" (a teacher's equal answer).
// With z = r_A − r_B and P(A ≻ B) = σ(z):
//   L = (1/B) Σ_i −[ℓ_i log σ(z_i) + (1 − ℓ_i) log σ(−z_i)]  +  λ · (1/B) Σ_i (r_A,i² + r_B,i²)
// (the L2 term is the batch mean of r_A² + r_B², as in the authors' lineage code).
// Writes ∂L/∂r into dr [2B] when not null.
template <typename T>
T bradley_terry_loss(const T* r, const T* label, int B, T l2_weight, T* dr);

// Fraction of pairs where the reward ranks the pair as the label does (labels of 0.5 skipped).
template <typename T>
double preference_accuracy(const T* r, const T* label, int B);

}  // namespace sirl
