#include "kernels/linear_probe.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace sirl {

using RowMatD = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMatF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

LinearProbe fit_linear_probe(const float* X, const float* Y, int n, int in, int out) {
  if (n < 1 || in < 0 || out < 1) throw std::invalid_argument("linear probe: empty training set");
  RowMatD A(n, in + 1);
  A.leftCols(in) = Eigen::Map<const RowMatF>(X, n, in).cast<double>();
  A.col(in).setOnes();
  const RowMatD b = Eigen::Map<const RowMatF>(Y, n, out).cast<double>();
  const RowMatD beta = n > in ? RowMatD(A.colPivHouseholderQr().solve(b))  // [in+1, out]
                              : RowMatD(A.completeOrthogonalDecomposition().solve(b));
  LinearProbe p;
  p.in = in;
  p.out = out;
  p.weights.assign(beta.data(), beta.data() + beta.size());
  return p;
}

RidgeProbe fit_ridge_probe_loocv(const float* X, const float* Y, int n, int in, int out) {
  if (n < 2 || in < 1 || out < 1)
    throw std::invalid_argument("ridge probe: needs >= 2 rows, >= 1 input and >= 1 output");
  using MatD = Eigen::MatrixXd;
  const MatD x = Eigen::Map<const RowMatF>(X, n, in).cast<double>();
  const MatD y = Eigen::Map<const RowMatF>(Y, n, out).cast<double>();
  const Eigen::RowVectorXd x_mean = x.colwise().mean(), y_mean = y.colwise().mean();
  const MatD xc = x.rowwise() - x_mean, yc = y.rowwise() - y_mean;
  // Xc = Z Qᵀ with Q [in, k] orthonormal and Z [n, k] orthogonal columns of squared norms λ:
  // from the eigendecomposition of the smaller Gram matrix.
  const bool primal = in <= n;
  Eigen::SelfAdjointEigenSolver<MatD> eig(primal ? MatD(xc.transpose() * xc)
                                                 : MatD(xc * xc.transpose()));
  const Eigen::VectorXd& all = eig.eigenvalues();
  const double top = all.size() ? all(all.size() - 1) : 0.0;
  std::vector<int> keep;
  for (int j = 0; j < int(all.size()); ++j)
    if (all(j) > 1e-12 * top && all(j) > 0) keep.push_back(j);
  const int k = int(keep.size());
  MatD E(eig.eigenvectors().rows(), k);
  Eigen::VectorXd lambda(k);
  for (int j = 0; j < k; ++j) {
    E.col(j) = eig.eigenvectors().col(keep[size_t(j)]);
    lambda(j) = all(keep[size_t(j)]);
  }
  const MatD Z = primal ? MatD(xc * E) : MatD(E * lambda.cwiseSqrt().asDiagonal());
  const MatD Q =
      primal ? E : MatD(xc.transpose() * E * lambda.cwiseSqrt().cwiseInverse().asDiagonal());
  const MatD Zty = Z.transpose() * yc;  // [k, out]
  const double scale = k ? lambda.sum() / k : 1.0;
  RidgeProbe best;
  best.loo_mse = std::numeric_limits<double>::infinity();
  MatD best_gamma;
  for (int p = -8; p <= 2; ++p) {
    const double a = scale * std::pow(10.0, p);
    const Eigen::VectorXd shrink = (lambda.array() + a).inverse().matrix();  // 1/(λ + a)
    const MatD gamma = shrink.asDiagonal() * Zty;                            // [k, out]
    const MatD resid = yc - Z * gamma;
    // leverage of row i: Σ_j Z_ij² / (λ_j + a), plus 1/n for the fitted mean
    const Eigen::VectorXd h = (Z.array().square().matrix() * shrink).array() + 1.0 / n;
    double loo = 0;
    for (int i = 0; i < n; ++i) loo += (resid.row(i) / (1.0 - h(i))).squaredNorm();
    loo /= double(n) * out;
    if (loo < best.loo_mse) {
      best.loo_mse = loo;
      best.weight = a;
      best_gamma = gamma;
    }
  }
  const MatD beta = k ? MatD(Q * best_gamma) : MatD::Zero(in, out);  // [in, out]
  RowMatD w(in + 1, out);
  w.topRows(in) = beta;
  w.row(in) = y_mean - x_mean * beta;
  best.probe.in = in;
  best.probe.out = out;
  best.probe.weights.assign(w.data(), w.data() + w.size());
  return best;
}

double linear_probe_mse(const LinearProbe& p, const float* X, const float* Y, int n) {
  if (n < 1) throw std::invalid_argument("linear probe: empty test set");
  Eigen::Map<const RowMatD> beta(p.weights.data(), p.in + 1, p.out);
  const RowMatD x = Eigen::Map<const RowMatF>(X, n, p.in).cast<double>();
  const RowMatD y = Eigen::Map<const RowMatF>(Y, n, p.out).cast<double>();
  RowMatD pred = x * beta.topRows(p.in);
  pred.rowwise() += beta.row(p.in);
  return (pred - y).squaredNorm() / (double(n) * p.out);
}

}  // namespace sirl
