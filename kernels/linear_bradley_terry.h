// A linear Bradley–Terry reward head on fixed features, as linear evaluation fits it (engine/
// linear_tpa.h): L2-regularised logistic regression on standardised features, its penalty chosen
// by cross-validation on the training pairs only (the standard linear-evaluation read-out).
//
// Each feature is standardised over the fit's own 2M training rows (x̃ = (x − μ)/σ; a feature
// with σ = 0 there gets no weight), and with r(x) = w·x̃ the loss is
//   L(w) = (1/M) Σ_i BCE(σ(r(A_i) − r(B_i)), ℓ_i) + α ‖w‖².
// A bias cancels in r(A) − r(B), so the head has none (the rewards are centred on the training
// rows). By the representer theorem the minimiser lies in the span of the pair differences
// x̃_A − x̃_B; the fit runs there (Newton with backtracking from 0), so a 2037-wide input costs no
// more than its M pairs. With α > 0 the loss is strictly convex: the minimiser is unique.
#pragma once
#include <cstdint>
#include <vector>

namespace sirl {

struct LinearBtOptions {
  // The penalties cross-validation chooses from (ascending), and the folds (pair i is in fold
  // i mod folds; fewer pairs than folds: leave one out). With one pair there is nothing to
  // validate on: `single_pair_alpha` is used.
  std::vector<double> alpha_grid{1e-4, 1e-3, 1e-2, 1e-1, 1, 10, 100};
  int folds = 5;
  double single_pair_alpha = 1;
  // Stop when half the squared Newton decrement, an estimate of L − min L near the optimum, is at
  // most this (Newton converges quadratically: a few steps past 1e-12 reach it), or when it is at
  // most `floor` and no step lowers L at working precision.
  double tolerance = 1e-20;
  double floor = 1e-12;
  int max_iterations = 100;
  // Directions of the pair differences' span whose squared singular value is below this
  // fraction of the largest are dropped (numerically no direction).
  double rank_tolerance = 1e-12;
};

struct LinearBtFit {
  std::vector<double> weights;  // [in + 1]: w/σ per input feature, then −Σ w μ/σ (original units)
  double alpha = 0;             // the penalty of this fit
  int iterations = 0;           // Newton steps taken (of the final fit, for a cross-validated one)
  bool converged = false;       // every fit's decrement fell below the tolerance within the cap
  double decrement = 0;         // half the squared Newton decrement at the end
  int rank = 0;                 // dimension of the pair differences' span the fit ran in
  double cv_loss = 0;           // held-out BCE per pair at the chosen α (cross-validated fits)
  double flops = 0;             // floating-point operations executed (an estimate by counts)
};

// One fit at penalty alpha > 0. X [n, in] row-major features; pairs [2M]: pair i is (A, B) =
// rows (pairs[2i], pairs[2i+1]) of X; label [M] ∈ [0, 1] (1: A preferred, 0.5: equal). Double
// precision throughout. Throws std::invalid_argument if M < 1, in < 1, alpha ≤ 0 or a row index
// is outside [0, n).
LinearBtFit fit_linear_bradley_terry(const float* X, int64_t n, int in, const int32_t* pairs,
                                     const float* label, int M, double alpha,
                                     const LinearBtOptions& o = {});

// α chosen from o.alpha_grid by the held-out BCE of o.folds-fold cross-validation over the M
// pairs (the largest α of equal loss wins), then refit on all M pairs at that α. Each fold's
// standardisation and span are built once and shared by every α of the grid: the same bits as
// fitting each (fold, α) alone, in a fraction of the work when the features are wide.
LinearBtFit fit_linear_bradley_terry_cv(const float* X, int64_t n, int in, const int32_t* pairs,
                                        const float* label, int M, const LinearBtOptions& o = {});

// The fit's rewards r [count] of rows `rows` of X [n, in].
std::vector<double> linear_rewards(const LinearBtFit& f, const float* X, int in,
                                   const int32_t* rows, int64_t count);

}  // namespace sirl
