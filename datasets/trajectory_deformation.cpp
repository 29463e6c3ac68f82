#include "datasets/trajectory_deformation.h"

#include <stdexcept>

namespace sirl {

namespace {
// Lower-triangle entries of one joint's block: (row, col, value) with row ≥ col.
template <typename F>
void for_each_entry(int m, F&& f) {
  for (int i = 0; i < m; ++i) {
    f(i, i, 6.0);
    if (i + 1 < m) f(i + 1, i, -4.0);
    if (i + 2 < m) f(i + 2, i, 1.0);
  }
}
}  // namespace

SparseCholesky DeformationNorm::factor(int m, int dofs) {
  if (m < 1 || dofs < 1)
    throw std::invalid_argument("DeformationNorm: need at least 3 waypoints and 1 joint");
  std::vector<int> r, c;
  std::vector<double> v;
  for (int j = 0; j < dofs; ++j)
    for_each_entry(m, [&](int row, int col, double x) {
      r.push_back(j * m + row);
      c.push_back(j * m + col);
      v.push_back(x);
    });
  return SparseCholesky(m * dofs, r, c, v);
}

DeformationNorm::DeformationNorm(int waypoints, int dofs)
    : m_(waypoints - 2), dofs_(dofs), chol_(factor(waypoints - 2, dofs)) {}

std::vector<double> DeformationNorm::dense_matrix() const {
  const int n = size();
  std::vector<double> A(size_t(n) * n, 0.0);
  for (int j = 0; j < dofs_; ++j)
    for_each_entry(m_, [&](int row, int col, double x) {
      A[size_t(j * m_ + row) * n + j * m_ + col] = x;
      A[size_t(j * m_ + col) * n + j * m_ + row] = x;
    });
  return A;
}

}  // namespace sirl
