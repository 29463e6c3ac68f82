#include "kernels/linear_probe.h"

#include <Eigen/Dense>
#include <stdexcept>

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
