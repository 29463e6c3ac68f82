// The FPE probe: least squares Y ≈ [X 1]·β with a bias, solved in closed form (double precision).
#pragma once
#include <vector>

namespace sirl {

struct LinearProbe {
  int in = 0, out = 0;
  std::vector<double> weights;  // [in + 1, out]: rows 0..in−1 for the inputs, row `in` the bias
};

// X [n, in], Y [n, out] row-major. Column-pivoting QR, so rank-deficient X (dead or constant
// embedding units) still gives the minimum-residual fit. With fewer rows than unknowns (n ≤ in:
// a wide input such as the raw reference's) the residual is zero for many β, and the one of least
// norm is taken (complete orthogonal decomposition; the limit of ridge as its weight goes to 0).
// Throws std::invalid_argument if n < 1.
LinearProbe fit_linear_probe(const float* X, const float* Y, int n, int in, int out);

// Ridge regression with a bias (not penalised), its weight chosen by leave-one-out error on the n
// rows themselves: the probe of an input far wider than its rows (the raw reference: 800 rows of
// 2037 inputs on JacoRobot), where least squares fits the rows exactly and says nothing. The
// candidate weights are s · 10^p, p = −8 … 2, with s the mean squared singular value of the
// centred X (so the grid follows X's scale); the first with the least leave-one-out mean squared
// error wins (closed form: residual / (1 − leverage)). Throws std::invalid_argument if n < 2.
struct RidgeProbe {
  LinearProbe probe;
  double weight = 0;   // the chosen ridge weight
  double loo_mse = 0;  // its leave-one-out mean squared error
};
RidgeProbe fit_ridge_probe_loocv(const float* X, const float* Y, int n, int in, int out);

// Mean over the n·out entries of (prediction − Y)².
double linear_probe_mse(const LinearProbe& probe, const float* X, const float* Y, int n);

}  // namespace sirl
