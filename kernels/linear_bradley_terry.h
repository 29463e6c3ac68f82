// A linear Bradley–Terry reward head on fixed features, fit to convergence: the linear-evaluation
// protocol of TPA (engine/linear_tpa.h). The loss is the paper's head loss
// (kernels/bradley_terry_loss.h) with r(x) = w·x + c:
//   L(w, c) = (1/M) Σ_i BCE(σ(r(A_i) − r(B_i)), ℓ_i) + λ (1/M) Σ_i (r(A_i)² + r(B_i)²).
// L depends on (w, c) only through the rewards of the 2M training rows, so its minimisers form an
// affine set along directions no training row sees; the fit returns the one of least norm (the
// minimiser within the span of the training rows [x 1]). With λ > 0, L is strictly convex on that
// span and Newton's method (with backtracking) converges to its unique minimiser from 0.
#pragma once
#include <cstdint>
#include <vector>

namespace sirl {

struct LinearBtOptions {
  double l2 = 10;  // λ: the paper's L2 weight on the predicted rewards (tpa.l2)
  // Stop when half the squared Newton decrement, an estimate of L − min L near the optimum, is at
  // most this (Newton converges quadratically: a few steps past 1e-12 reach it), or when it is at
  // most `floor` and no step lowers L at working precision.
  double tolerance = 1e-20;
  double floor = 1e-12;
  int max_iterations = 100;
  // Directions of the training rows' span whose squared singular value is below this fraction of
  // the largest are dropped (numerically no direction: constant or dead features).
  double rank_tolerance = 1e-12;
};

struct LinearBtFit {
  std::vector<double> weights;  // [in + 1]: w, then the bias c
  int iterations = 0;           // Newton steps taken
  bool converged = false;       // the decrement fell below the tolerance within the cap
  double decrement = 0;         // half the squared Newton decrement at the end
  int rank = 0;                 // dimension of the training rows' span the fit ran in
  double flops = 0;             // floating-point operations executed (an estimate by counts)
};

// X [n, in] row-major features; pairs [2M]: pair i is (A, B) = rows (pairs[2i], pairs[2i+1]) of X;
// label [M] ∈ [0, 1] (1: A preferred, 0.5: equal). Double precision throughout. Throws
// std::invalid_argument if M < 1, in < 1 or a row index is outside [0, n).
LinearBtFit fit_linear_bradley_terry(const float* X, int64_t n, int in, const int32_t* pairs,
                                     const float* label, int M, const LinearBtOptions& o = {});

// The fit's rewards r [count] of rows `rows` of X [n, in].
std::vector<double> linear_rewards(const LinearBtFit& f, const float* X, int in,
                                   const int32_t* rows, int64_t count);

}  // namespace sirl
