// Smooth trajectory deformations (Dragan et al.'s trajectory-deformation norm, as in the SIRL
// appendix): ξ_D = ξ + μ A⁻¹ ũ with A = KᵀK, K the finite-difference acceleration operator.
// Start and goal stay fixed, so A acts on the interior waypoints only; one block per joint.
#pragma once
#include <vector>

#include "kernels/sparse_cholesky.h"

namespace sirl {

class DeformationNorm {
 public:
  // waypoints ≥ 3 (interior m = waypoints − 2), dofs ≥ 1. Factors A once (CHOLMOD).
  DeformationNorm(int waypoints, int dofs);
  int interior() const { return m_; }
  int dofs() const { return dofs_; }
  int size() const { return m_ * dofs_; }
  // Vector layout: index j·m + i = joint j at interior waypoint i (waypoint i + 1).
  // Per joint, K [(m+2), m] has columns (…, 1, −2, 1, …) so A = KᵀK is pentadiagonal
  // (6 on the diagonal, −4 and 1 beside it).
  std::vector<double> dense_matrix() const;  // [size, size] row-major, for tests
  // Solves A X = B for k right-hand sides, B [size, k] column-major, overwritten.
  void solve(double* B, int k) const { chol_.solve(B, k); }

 private:
  static SparseCholesky factor(int m, int dofs);
  int m_, dofs_;
  SparseCholesky chol_;
};

}  // namespace sirl
