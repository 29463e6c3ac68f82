#include "kernels/linear_bradley_terry.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace sirl {

namespace {
using MatD = Eigen::MatrixXd;
using VecD = Eigen::VectorXd;

double sigmoid(double z) {
  return z >= 0 ? 1.0 / (1.0 + std::exp(-z)) : std::exp(z) / (1.0 + std::exp(z));
}
double softplus(double z) {
  return z > 0 ? z + std::log1p(std::exp(-z)) : std::log1p(std::exp(z));
}

// BCE(σ(z), ℓ) = ℓ·softplus(−z) + (1 − ℓ)·softplus(z), the loss of one pair.
double pair_bce(double z, double label) {
  return label * softplus(-z) + (1 - label) * softplus(z);
}

// An orthonormal basis Q [p, k] of the row span of A [m, p] and the rows' coordinates Z = A·Q
// [m, k], from the eigendecomposition of the smaller Gram matrix (AᵀA [p, p] when p ≤ m, else
// AAᵀ [m, m]: then Q = Aᵀ U Λ^{-1/2}, Z = U Λ^{1/2}).
struct SpanBasis {
  MatD Q, Z;
  double flops = 0;
};
SpanBasis span_basis(const MatD& A, double rank_tolerance) {
  const double m = double(A.rows()), p = double(A.cols());
  SpanBasis b;
  const bool primal = A.cols() <= A.rows();
  const MatD G = primal ? MatD(A.transpose() * A) : MatD(A * A.transpose());
  const double g = double(G.rows());
  b.flops = 2.0 * m * p * std::min(m, p) + 9.0 * g * g * g;  // Gram, then the eigensolver
  Eigen::SelfAdjointEigenSolver<MatD> eig(G);
  const VecD& lambda = eig.eigenvalues();  // ascending
  const double top = lambda.size() ? lambda(lambda.size() - 1) : 0.0;
  int first = int(lambda.size());
  while (first > 0 && lambda(first - 1) > rank_tolerance * top && lambda(first - 1) > 0) --first;
  const int k = int(lambda.size()) - first;
  const MatD U = eig.eigenvectors().rightCols(k);
  const VecD s = lambda.tail(k).cwiseSqrt();
  if (primal) {
    b.Q = U;
    b.Z = A * U;
  } else {
    b.Q = A.transpose() * U * s.cwiseInverse().asDiagonal();
    b.Z = U * s.asDiagonal();
  }
  b.flops += 2.0 * m * p * k;
  return b;
}

// L(β) = (1/M) Σ BCE(σ(z_i), ℓ_i) + α‖β‖² at z = Zβ, with ∂L/∂z into dz.
double loss_at(const MatD& Z, const VecD& beta, const std::vector<double>& label, double alpha,
               VecD& z, VecD& dz) {
  z = Z * beta;
  const double M = double(label.size());
  dz.resize(z.size());
  double L = 0;
  for (Eigen::Index i = 0; i < z.size(); ++i) {
    L += pair_bce(z(i), label[size_t(i)]) / M;
    dz(i) = (sigmoid(z(i)) - label[size_t(i)]) / M;
  }
  return L + alpha * beta.squaredNorm();
}

void check_rows(const int32_t* pairs, int M, int64_t n) {
  for (int i = 0; i < 2 * M; ++i)
    if (pairs[i] < 0 || pairs[i] >= n)
      throw std::invalid_argument("linear Bradley–Terry fit: row " + std::to_string(pairs[i]) +
                                  " outside [0, " + std::to_string(n) + ")");
}

// What a fit on one set of training pairs needs before its penalty is known: the features'
// standardisation over the 2M rows and the span of the pair differences. Cross-validation fits
// every penalty of its grid on the same folds, so it builds this once per fold, not once per
// (fold, penalty): the Gram matrix and its eigensolver are most of a wide fit's work.
struct PairSpan {
  VecD mu, inv;  // [in] the training rows' means and 1/σ (0 for a constant feature)
  SpanBasis b;   // Q [in, k], Z [M, k]
  double flops = 0;
};

PairSpan pair_span(const float* X, int in, const int32_t* pairs, int M, double rank_tolerance) {
  auto x = [&](int32_t row, int j) { return double(X[int64_t(row) * in + j]); };
  PairSpan s;
  // μ, σ [in] over the 2M training rows (two passes); σ = 0 (a constant feature) → no weight.
  s.mu = VecD::Zero(in);
  VecD& mu = s.mu;
  VecD sd = VecD::Zero(in);
  for (int i = 0; i < 2 * M; ++i)
    for (int j = 0; j < in; ++j) mu(j) += x(pairs[i], j) / (2.0 * M);
  for (int i = 0; i < 2 * M; ++i)
    for (int j = 0; j < in; ++j) sd(j) += std::pow(x(pairs[i], j) - mu(j), 2) / (2.0 * M);
  s.inv = VecD::Zero(in);
  for (int j = 0; j < in; ++j) {
    const double sj = std::sqrt(sd(j));
    if (sj > 1e-10 * std::abs(mu(j)) && sj > 0) s.inv(j) = 1.0 / sj;
  }
  // D [M, in]: the standardised differences x̃_A − x̃_B.
  MatD D(M, in);
  for (int i = 0; i < M; ++i)
    for (int j = 0; j < in; ++j) D(i, j) = (x(pairs[2 * i], j) - x(pairs[2 * i + 1], j)) * s.inv(j);
  s.b = span_basis(D, rank_tolerance);
  s.flops = 6.0 * M * in + s.b.flops;
  return s;
}

// The Newton fit at penalty alpha in a prepared span; label [M] as the span's pairs.
LinearBtFit fit_in_span(const PairSpan& s, const float* label, int M, double alpha,
                        const LinearBtOptions& o) {
  const int in = int(s.mu.size());
  const std::vector<double> lab(label, label + M);
  const MatD& Z = s.b.Z;
  const int k = int(Z.cols());
  LinearBtFit f;
  f.alpha = alpha;
  f.rank = k;
  VecD beta = VecD::Zero(k), z, dz, z_try, dz_try;
  double L = loss_at(Z, beta, lab, alpha, z, dz);
  while (k > 0 && f.iterations < o.max_iterations) {
    const VecD grad = Z.transpose() * dz + 2 * alpha * beta;
    // H = Zᵀ diag(σ(z)σ(−z)/M) Z + 2α I.
    VecD w(M);
    for (int i = 0; i < M; ++i) w(i) = sigmoid(z(i)) * sigmoid(-z(i)) / M;
    MatD H = Z.transpose() * w.asDiagonal() * Z;
    H.diagonal().array() += 2 * alpha;
    const VecD step = -H.ldlt().solve(grad);
    f.flops += 2.0 * M * k * (2 + k) + double(k) * k * k / 3;
    f.decrement = -0.5 * grad.dot(step);
    if (!(f.decrement > o.tolerance)) {  // NaN (no curvature) stops too, unconverged
      f.converged = f.decrement <= o.tolerance;
      break;
    }
    ++f.iterations;
    double t = 1;  // backtracking (Armijo) from the full Newton step
    double L_try = loss_at(Z, beta + t * step, lab, alpha, z_try, dz_try);
    for (int h = 0; h < 60 && !(L_try <= L + 1e-4 * t * grad.dot(step)); ++h) {
      t *= 0.5;
      L_try = loss_at(Z, beta + t * step, lab, alpha, z_try, dz_try);
    }
    if (!(L_try < L)) {  // no descent left at working precision
      f.converged = f.decrement <= o.floor;
      break;
    }
    beta += t * step;
    L = L_try;
    z.swap(z_try);
    dz.swap(dz_try);
  }
  if (k == 0) f.converged = true;  // no direction to fit: every reward is 0
  // Back to the original units: r(x) = Σ_j w̃_j (x_j − μ_j)/σ_j.
  const VecD wt = k ? VecD(s.b.Q * beta) : VecD::Zero(in);
  f.weights.assign(size_t(in) + 1, 0.0);
  for (int j = 0; j < in; ++j) {
    f.weights[size_t(j)] = wt(j) * s.inv(j);
    f.weights[size_t(in)] -= wt(j) * s.inv(j) * s.mu(j);
  }
  return f;
}
}  // namespace

LinearBtFit fit_linear_bradley_terry(const float* X, int64_t n, int in, const int32_t* pairs,
                                     const float* label, int M, double alpha,
                                     const LinearBtOptions& o) {
  if (M < 1 || in < 1)
    throw std::invalid_argument("linear Bradley–Terry fit: needs M >= 1 pairs of >= 1 features");
  if (!(alpha > 0))
    throw std::invalid_argument("linear Bradley–Terry fit: the penalty must be > 0");
  check_rows(pairs, M, n);
  const PairSpan s = pair_span(X, in, pairs, M, o.rank_tolerance);
  LinearBtFit f = fit_in_span(s, label, M, alpha, o);
  f.flops += s.flops;
  return f;
}

LinearBtFit fit_linear_bradley_terry_cv(const float* X, int64_t n, int in, const int32_t* pairs,
                                        const float* label, int M, const LinearBtOptions& o) {
  if (o.alpha_grid.empty() || o.folds < 2)
    throw std::invalid_argument("linear Bradley–Terry fit: needs a penalty grid and >= 2 folds");
  if (M < 2) return fit_linear_bradley_terry(X, n, in, pairs, label, M, o.single_pair_alpha, o);
  if (in < 1)
    throw std::invalid_argument("linear Bradley–Terry fit: needs M >= 1 pairs of >= 1 features");
  for (double alpha : o.alpha_grid)
    if (!(alpha > 0))
      throw std::invalid_argument("linear Bradley–Terry fit: the penalty must be > 0");
  check_rows(pairs, M, n);
  const int folds = std::min(o.folds, M);
  const size_t grid = o.alpha_grid.size();
  double flops = 0;
  bool converged = true;
  // held[a]: Σ over every pair of its BCE when its fold was held out, at penalty alpha_grid[a]
  // (summed fold by fold in fold order, whatever the loop nesting).
  std::vector<double> held(grid, 0.0);
  for (int fold = 0; fold < folds; ++fold) {
    std::vector<int32_t> fit_pairs, held_pairs;
    std::vector<float> fit_label;
    std::vector<double> held_label;
    for (int i = 0; i < M; ++i) {
      auto& dst = i % folds == fold ? held_pairs : fit_pairs;
      dst.push_back(pairs[2 * i]);
      dst.push_back(pairs[2 * i + 1]);
      if (i % folds == fold)
        held_label.push_back(label[i]);
      else
        fit_label.push_back(label[i]);
    }
    const int m = int(fit_label.size());
    const PairSpan s = pair_span(X, in, fit_pairs.data(), m, o.rank_tolerance);
    flops += s.flops;
    for (size_t a = 0; a < grid; ++a) {
      const LinearBtFit f = fit_in_span(s, fit_label.data(), m, o.alpha_grid[a], o);
      flops += f.flops;
      converged = converged && f.converged;
      const std::vector<double> r =
          linear_rewards(f, X, in, held_pairs.data(), int64_t(held_pairs.size()));
      for (size_t i = 0; i < held_label.size(); ++i)
        held[a] += pair_bce(r[2 * i] - r[2 * i + 1], held_label[i]);
    }
  }
  double best = INFINITY, best_alpha = o.alpha_grid.front();
  for (size_t a = 0; a < grid; ++a) {
    const double held_loss = held[a] / M;
    // Ascending grid: a larger α of equal loss (up to rounding) wins, the simpler head.
    if (held_loss <= best + 1e-12 * std::abs(best) || !std::isfinite(best)) {
      best = held_loss;
      best_alpha = o.alpha_grid[a];
    }
  }
  LinearBtFit f = fit_linear_bradley_terry(X, n, in, pairs, label, M, best_alpha, o);
  f.cv_loss = best;
  f.flops += flops;
  f.converged = f.converged && converged;
  return f;
}

std::vector<double> linear_rewards(const LinearBtFit& f, const float* X, int in,
                                   const int32_t* rows, int64_t count) {
  if (int(f.weights.size()) != in + 1)
    throw std::invalid_argument("linear rewards: the fit has " + std::to_string(f.weights.size()) +
                                " weights, the rows " + std::to_string(in) + " features");
  std::vector<double> r(static_cast<size_t>(count));
  for (int64_t i = 0; i < count; ++i) {
    const float* x = X + int64_t(rows[i]) * in;
    double s = f.weights[size_t(in)];
    for (int j = 0; j < in; ++j) s += f.weights[size_t(j)] * double(x[j]);
    r[size_t(i)] = s;
  }
  return r;
}

}  // namespace sirl
