#include "kernels/linear_bradley_terry.h"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>
#include <string>

#include "kernels/bradley_terry_loss.h"

namespace sirl {

namespace {
using MatD = Eigen::MatrixXd;
using VecD = Eigen::VectorXd;

double sigmoid(double z) {
  return z >= 0 ? 1.0 / (1.0 + std::exp(-z)) : std::exp(z) / (1.0 + std::exp(z));
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

// L(β) of the rewards r = Zβ (rows 0..M−1 the A's, M..2M−1 the B's), with ∂L/∂r into dr.
double loss_at(const MatD& Z, const VecD& beta, const std::vector<double>& label, double l2,
               VecD& r, VecD& dr) {
  r = Z * beta;
  dr.resize(r.size());
  return bradley_terry_loss<double>(r.data(), label.data(), int(label.size()), l2, dr.data());
}
}  // namespace

LinearBtFit fit_linear_bradley_terry(const float* X, int64_t n, int in, const int32_t* pairs,
                                     const float* label, int M, const LinearBtOptions& o) {
  if (M < 1 || in < 1)
    throw std::invalid_argument("linear Bradley–Terry fit: needs M >= 1 pairs of >= 1 features");
  // A [2M, in + 1]: the A rows, then the B rows, each with a 1 for the bias.
  MatD A(2 * M, in + 1);
  for (int i = 0; i < 2 * M; ++i) {
    const int32_t row = pairs[i < M ? 2 * i : 2 * (i - M) + 1];
    if (row < 0 || row >= n)
      throw std::invalid_argument("linear Bradley–Terry fit: row " + std::to_string(row) +
                                  " outside [0, " + std::to_string(n) + ")");
    for (int j = 0; j < in; ++j) A(i, j) = X[int64_t(row) * in + j];
    A(i, in) = 1.0;
  }
  std::vector<double> lab(label, label + M);
  const SpanBasis b = span_basis(A, o.rank_tolerance);
  const MatD& Z = b.Z;
  const int k = int(Z.cols());
  LinearBtFit f;
  f.rank = k;
  f.flops = b.flops;
  VecD beta = VecD::Zero(k), r, dr, r_try, dr_try;
  double L = loss_at(Z, beta, lab, o.l2, r, dr);
  const double l2_curv = 2.0 * o.l2 / M;  // ∂²(λ/M Σ r²)/∂r²
  while (k > 0 && f.iterations < o.max_iterations) {
    const VecD grad = Z.transpose() * dr;
    // H = Zᵀ W Z, W = ∂²L/∂r²: σσ'/M on each pair's difference, 2λ/M on every reward.
    MatD WZ = l2_curv * Z;
    for (int i = 0; i < M; ++i) {
      const double z = r(i) - r(M + i), s = sigmoid(z) * sigmoid(-z) / M;
      const auto diff = (Z.row(i) - Z.row(M + i)).eval();
      WZ.row(i) += s * diff;
      WZ.row(M + i) -= s * diff;
    }
    const MatD H = Z.transpose() * WZ;
    const VecD step = -H.ldlt().solve(grad);
    f.flops += 2.0 * double(2 * M) * k * (2 + 2 * k) + double(k) * k * k / 3;
    f.decrement = -0.5 * grad.dot(step);
    if (!(f.decrement > o.tolerance)) {  // NaN (no curvature) stops too, unconverged
      f.converged = f.decrement <= o.tolerance;
      break;
    }
    ++f.iterations;
    double t = 1;  // backtracking (Armijo) from the full Newton step
    double L_try = loss_at(Z, beta + t * step, lab, o.l2, r_try, dr_try);
    for (int h = 0; h < 60 && !(L_try <= L + 1e-4 * t * grad.dot(step)); ++h) {
      t *= 0.5;
      L_try = loss_at(Z, beta + t * step, lab, o.l2, r_try, dr_try);
    }
    if (!(L_try < L)) {  // no descent left at working precision
      f.converged = f.decrement <= o.floor;
      break;
    }
    beta += t * step;
    L = L_try;
    r.swap(r_try);
    dr.swap(dr_try);
  }
  if (k == 0) f.converged = true;  // no direction to fit: every reward is 0
  const VecD theta = k ? VecD(b.Q * beta) : VecD::Zero(in + 1);
  f.weights.assign(theta.data(), theta.data() + theta.size());
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
