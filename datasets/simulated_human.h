// Simulated humans answering similarity and preference queries from the true features φ*
// (normalised). Shared by GridRobot and JacoRobot.
//
// A Teacher carries the B-Pref benchmark's noise models (Lee et al. 2021), applied to both
// query kinds:
//   beta       Boltzmann rationality; +inf = the paper's perfect oracle, 0 = answers uniformly
//              at random.
//              similarity: P(pair k are the positives) ∝ exp(−β·d_k), d_k = ‖φ*_i − φ*_j‖²
//              preference: P(A ≻ B) = σ(β·(R_A − R_B)), R = w·φ*
//   mistake    probability ε of flipping the answer (similarity: another pair, uniformly)
//   skip       answer withheld when the options are too alike:
//              similarity: max_k d_k − min_k d_k < skip;  preference: |R_A − R_B| < skip
//   equal      near-ties: preference → label 0.5 when |R_A − R_B| < equal;
//              similarity → a coin flip between the pairs within `equal` of the closest
//   mask       features the teacher perceives (empty = all); others are ignored by both oracles
#pragma once
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "kernels/rng.h"

namespace sirl {

struct Teacher {
  double beta = std::numeric_limits<double>::infinity();
  double mistake = 0.0;
  double skip = 0.0;
  double equal = 0.0;
  std::vector<uint8_t> mask;  // [F] 1 = perceived; empty = all features

  bool perfect() const {
    return beta == std::numeric_limits<double>::infinity() && mistake == 0 && skip == 0 &&
           equal == 0;
  }
};

// Throws std::invalid_argument for β < 0, ε ∉ [0, 1], negative thresholds, or a mask whose
// length is not F or that hides every feature.
void validate(const Teacher& t, int feature_count);

// Positions (0, 1, 2) of (ξ1, ξ2, ξ3) reordered as (positive 1, positive 2, negative).
struct TripletAnswer {
  int p1, p2, neg;
};

// f1, f2, f3: normalised φ* [F] of the three trajectories. nullopt = skipped.
std::optional<TripletAnswer> answer_similarity(const Teacher& t, const float* f1, const float* f2,
                                               const float* f3, int F, Rng& rng);

// Label ∈ {0, 0.5, 1} (1 = A preferred) under reward R = w·(mask ⊙ φ*). nullopt = skipped.
std::optional<float> answer_preference(const Teacher& t, const float* w, const float* fa,
                                       const float* fb, int F, Rng& rng);

double reward(const float* w, const float* f, int F, const std::vector<uint8_t>& mask = {});

}  // namespace sirl
